// The push block of the shading pass (shade.vert, shade.frag, shade_pixel.frag), mirrored by
// `ShadePush` in src/render/shade.rs (tests/render_records.rs pins the layout).
#ifndef SHADE_PUSH_GLSL
#define SHADE_PUSH_GLSL

// The object's material is here rather than read from its ObjectRecord: a CPU driver loads a
// storage buffer lane by lane in a fragment shader, and push constants at fixed offsets once.
struct ShadePush {
    mat4 view_proj;
    vec4 eye_object;        // xyz: camera position; w: object index
    uvec4 counts;           // x: light count; y: key (non-environment) lights, first in the buffer;
                            // z: the object's locally computed channels (ObjectRecord::local_channels);
                            // w: terms left out, to measure their cost (SHADE_SKIP_*)
    vec4 albedo_roughness;  // the object's ObjectRecord::albedo_roughness
    vec4 material;          // x: eta (ObjectRecord::eta); y: BSSRDF normalization (ObjectRecord::norm); zw: 0
};
layout(push_constant) uniform ShadePushBlock { ShadePush push; };

// Bits of counts.w, mirrored by shade::TERM_* in src/render/shade.rs.
const uint SHADE_SKIP_SHADOW = 1u;
const uint SHADE_SKIP_SPECULAR = 2u;
const uint SHADE_SKIP_FRESNEL = 4u;
const uint SHADE_SKIP_ALL = 8u;

bool shade_skips(uint term) {
    return (push.counts.w & term) != 0u;
}

#endif

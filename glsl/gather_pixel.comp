#version 450
// Pixel gather: the dipole sum (glsl/common/gather.glsl) at every pixel that shows a translucent
// object, for scenes with `render.gather = "pixel"`: exact at each visible point instead of
// interpolated from the vertices, and only where the surface is seen. The shading pass left the
// pixel's world position and object in the surface image and the factor F_t(cos theta_o)/(pi T)
// in the HDR alpha; this pass adds the exitance times that factor to the HDR radiance.
//
// Bindings: 0 = surface (combined sampler, rgba32f), 1 = samples (SampleRecord[]), 2 = splat
// (SplatRecord[]), 3 = objects (ObjectRecord[]), 4 = HDR radiance (storage image, rgba32f).
// Push: GatherPixelPush.
#include "dipole.glsl"
#include "scene.glsl"
#define GATHER_TRACK_NEAREST
#include "gather.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D surface;
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(set = 0, binding = 4, rgba32f) uniform image2D hdr;
struct GatherPixelPush {
    uint width;
    uint height;
};
layout(push_constant) uniform GatherPixelPushBlock { GatherPixelPush push; };

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(push.width) || p.y >= int(push.height)) return;
    vec4 s = texelFetch(surface, p, 0);
    vec4 radiance = imageLoad(hdr, p);
    if (s.w < 0.5) {
        // Not translucent: the alpha held no factor; restore it to opaque for the EXR.
        imageStore(hdr, p, vec4(radiance.rgb, 1.0));
        return;
    }
    ObjectRecord o = objects[uint(s.w - 0.5)];
    // Local channels were shaded whole by shade_pixel.frag.
    vec3 gathered = object_gathered_channels(o);
    if (gathered == vec3(0.0)) {
        imageStore(hdr, p, vec4(radiance.rgb, 1.0));
        return;
    }
    uint first = o.ranges.z, count = o.ranges.w;
    DipoleChannel ch[3] = gather_channels(o);
    GatherSum g = gather_begin();
    for (uint i = first; i < first + count; ++i) {
        gather_add(g, ch, o.near_blend.rgb, s.xyz, samples[i].position_area, splat[i].irradiance_area.rgb, splat[i].near_energy.rgb);
        if (((i - first) & 63u) == 63u) gather_flush(g);
    }
    // A pixel does not know its distance to an open boundary: the near field is taken whole
    // (the vertex gathers correct it; docs/STUDY.md, defect 3).
    vec2 no_boundary = vec2(GATHER_NO_BOUNDARY);
    imageStore(hdr, p, vec4(radiance.rgb + gather_end(g, ch, no_boundary) * gathered * radiance.a, 1.0));
}

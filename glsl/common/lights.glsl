// Light records (std430), mirrored by `LightGpu` in src/scene/lights.rs (a test pins the layout),
// and the shadow lookup shared by the splat (compute) and shading (fragment) passes.
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL

const uint LIGHT_DIRECTIONAL = 0u;
const uint LIGHT_POINT = 1u;
const uint LIGHT_SPOT = 2u;

struct Light {
    vec3 position;         // point, spot
    uint kind;             // LIGHT_*
    vec4 direction_cos;    // xyz: unit vector towards the light (directional) or the spot axis
                           //      pointing away from the light; w: cos of the spot's outer angle
    vec4 power_layer;      // rgb: irradiance W/m^2 (directional) or intensity W/sr (point, spot);
                           //      w: shadow-map layer, negative when the light casts no shadow
    vec4 spot_texel;       // x: cos of the spot's inner angle; y: shadow-map texel size in uv;
                           // z: normal offset (world units) against self-shadowing;
                           // w: 1 for a direction of the environment light, else 0
    mat4 shadow_matrix;    // world -> shadow clip space (depth 0..1)
};

// Environment directions light diffuse surfaces through the per-vertex cache of
// vertex_light.comp; the shading pass evaluates only the other lights per pixel.
bool light_is_environment(Light l) {
    return l.spot_texel.w > 0.5;
}

// Unit direction towards the light from `p`, and the irradiance it delivers to a surface facing
// it (inverse-square falloff and spot cone for local lights), before visibility and cosine.
void light_incidence(Light l, vec3 p, out vec3 wi, out vec3 irradiance) {
    uint kind = l.kind;
    if (kind == LIGHT_DIRECTIONAL) {
        wi = l.direction_cos.xyz;
        irradiance = l.power_layer.rgb;
        return;
    }
    vec3 d = l.position - p;
    float dist2 = max(dot(d, d), 1e-12);
    wi = d * inversesqrt(dist2);
    irradiance = l.power_layer.rgb / dist2;
    if (kind == LIGHT_SPOT) {
        float c = dot(-wi, l.direction_cos.xyz);
        irradiance *= smoothstep(l.direction_cos.w, l.spot_texel.x, c);
    }
}

// Where world point `p` (unit normal `n`, moved off the surface by the light's normal offset
// `spot_texel.z`) falls in light `l`'s shadow map: (u, v, layer, depth), false where the light
// casts no shadow or `p` lies behind its projection (lit either way). Beyond the far plane
// (receivers that cast no shadow can lie past the casters' sphere) the depth is the far plane's,
// so a texel that holds a caster still shadows and a cleared texel (depth 1) stays lit.
bool light_map_coord(Light l, vec3 p, vec3 n, out vec4 coord) {
    float layer = l.power_layer.w;
    coord = vec4(0.0);
    if (layer < 0.0) return false;
    vec4 clip = l.shadow_matrix * vec4(p + n * l.spot_texel.z, 1.0);
    if (clip.w <= 0.0) return false;
    vec3 ndc = clip.xyz / clip.w;
    coord = vec4(ndc.xy * 0.5 + 0.5, layer, min(ndc.z, 1.0));
    return true;
}
// Fraction of `l` that reaches world point `p` with unit normal `n` (1 = lit), from the light's
// shadow map through the compare sampler (each tap is itself a bilinear 2x2 percentage-closer
// filter when the format allows). `radius` 0 takes one tap (sharpest, for the splat's sparse
// sample points, closest to ray-cast visibility); 1 averages four taps around it (softer edges
// for shading pixels and vertices). Points outside the map are lit (border colour white). The lookup moves
// off the surface along the normal by half a texel (`spot_texel.z`), against self-shadowing.
float light_visibility(Light l, sampler2DArrayShadow maps, vec3 p, vec3 n, int radius) {
    vec4 coord;
    if (!light_map_coord(l, p, n, coord)) return 1.0;
    if (radius == 0) return texture(maps, coord);
    // Four bilinear compare taps half a texel off centre: a 3x3-texel tent filter from 16 texel
    // reads (a 3x3 grid of taps would read 36).
    float h = 0.5 * l.spot_texel.y;
    float lit = texture(maps, coord + vec4(-h, -h, 0.0, 0.0)) + texture(maps, coord + vec4(h, -h, 0.0, 0.0))
              + texture(maps, coord + vec4(-h, h, 0.0, 0.0)) + texture(maps, coord + vec4(h, h, 0.0, 0.0));
    return 0.25 * lit;
}

// The shadow-map compares of the four texels a one-tap `light_visibility` (radius 0) filters
// at `p` (1 = lit each); all 1 where the light casts no shadow or `p` lies outside its map.
vec4 light_texels(Light l, sampler2DArrayShadow maps, vec3 p, vec3 n) {
    vec4 coord;
    if (!light_map_coord(l, p, n, coord)) return vec4(1.0);
    return textureGather(maps, coord.xyz, coord.w);
}
#endif

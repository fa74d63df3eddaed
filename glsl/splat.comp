#version 450
// Irradiance splat: for every sample point, the irradiance transmitted into the medium from
// every light: sum over lights of E_light cos(theta_i) F_t(cos theta_i, eta) V, with V from the
// light's shadow map (one bilinear compare tap at the sample, no normal offset: the sharpest,
// closest to ray casting), from a shadow ray into the casters' hierarchy, or from the map where
// it is sure and a ray elsewhere (SPLAT_VISIBILITY). Also the sample's near-field energy per
// channel (dipole_near_energy), which depends only on its area and material, so that the gather
// pays for it once per sample instead of once per pair.
//
// The environment's directions (lights key_light_count..light_count) rarely change while a key
// light moves every frame, so their part is kept per sample (SplatEnvironment): a frame after a
// key light moved reads it back and loops over the key lights alone. The sum is taken in the same
// order either way (key lights + environment), so the kept splat equals a full one bit for bit;
// the near energy, written with the environment's part, is kept with it. The beam direction
// (SplatRecord::beam) is the key lights' alone, written every time: the environment's light
// arrives from everywhere.
//
// Bindings: 0 = samples (SampleRecord[], read), 1 = objects (ObjectRecord[], read),
// 2 = lights (Light[], read), 3 = shadow maps (sampler2DArrayShadow),
// 4 = splat output (SplatRecord[]), write, 5 = the environment's part (vec4 per sample), read
// when kept, else written, 6 = the casters' hierarchy (BvhNode[]), 7 = its triangles
// (BvhTriangle[]), both read.
// Push: SplatPush.
#include "dipole.glsl"
#include "lights.glsl"
#include "scene.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 1) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 2) readonly buffer Lights { Light lights[]; };
layout(set = 0, binding = 3) uniform sampler2DArrayShadow shadow_maps;
layout(std430, set = 0, binding = 4) writeonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 5) buffer SplatEnvironment { vec4 kept_environment[]; };
#define RAYS_NODES_BINDING 6
#define RAYS_TRIANGLES_BINDING 7
#include "rays.glsl"
struct SplatPush {
    uint object;            // one dispatch per object: its index and its samples
    uint first_sample;
    uint sample_count;
    uint light_count;       // all lights: key lights first, then the environment's directions
    uint key_light_count;
    uint environment_kept;  // 1: read the environment's part; 0: compute and keep it
    uint caster_triangles;  // triangles in bvh_triangles (0: nothing casts a shadow)
    float ray_offset;       // a ray leaves p + n ray_offset and counts hits past ray_offset
};
layout(push_constant) uniform SplatPushBlock { SplatPush push; };
// scene::SplatVisibility: 0 = the lights' shadow maps; 1 = shadow rays against the casters'
// hierarchy (exact, as the truth's: reference::transmitted_irradiance); 2 = hybrid, the map where
// it is sure and a ray where it is not.
layout(constant_id = 0) const uint SPLAT_VISIBILITY = 0u;
// The scene's key-light count where it is small (shade::unrolled_key_lights; 0: read
// push.key_light_count): the loop over them unrolls and each light's record is read at a
// constant index, once for all lanes, where a CPU driver loads at a varying index lane by lane.
layout(constant_id = 1) const uint SPLAT_KEY_LIGHTS = 0u;

// A shadow ray from the sample towards the light (as reference::transmitted_irradiance casts
// it): 1 when nothing blocks it.
float ray_visibility(Light l, vec3 p, vec3 n, vec3 wi) {
    if (push.caster_triangles == 0u) return 1.0;
    float t_max = l.kind == LIGHT_DIRECTIONAL ? 3.0e38 : length(l.position - p);
    return ray_occluded(p + n * push.ray_offset, wi, push.ray_offset, t_max) ? 0.0 : 1.0;
}

// Whether light `l` (direction `wi` from `p`, normal `n`) reaches the sample, which lies on a
// triangle of normal `face`.
float sample_visibility(Light l, vec3 p, vec3 n, vec3 wi, vec3 face) {
    if (l.power_layer.w < 0.0) return 1.0;
    if (SPLAT_VISIBILITY == 1u) return ray_visibility(l, p, n, wi);
    // Looked up at the sample itself, without the normal offset the shading pass takes
    // against acne: the truth casts its rays from the point (reference::ray_offset), and
    // the offset lit samples beside the terminator of coarse meshes that a ray finds
    // blocked (docs/STUDY.md, "Visibility in the splat"). The maps' slope-scaled depth
    // bias still keeps lit faces free of acne.
    Light unbiased = l;
    unbiased.spot_texel.z = 0.0;
    if (SPLAT_VISIBILITY == 0u) return light_visibility(unbiased, shadow_maps, p, n, 0);
    // Hybrid: the four texels the bilinear tap would read; where they agree and the triangle
    // faces the light, the map's answer is the ray's but for occluders thinner than a texel.
    // Beside a coarse mesh's terminator the triangle can face away while the normal faces the
    // light: the ray finds the mesh itself in the way, the map (its depth bias) does not.
    vec4 taps = light_texels(unbiased, shadow_maps, p, n);
    bool sure = dot(face, wi) > 1e-3 && all(equal(taps, taps.xxxx));
    return sure ? taps.x : ray_visibility(l, p, n, wi);
}

// Irradiance transmitted at `p` (normal `n`, face normal `face`, index ratio `eta`) from lights
// [first, end). `beam` gathers each light's refracted direction inside (Snell's law) weighted by
// the flux it transmits (the sum over channels), `flux` that flux.
vec3 transmitted(uint first, uint end, vec3 p, vec3 n, vec3 face, float eta, inout vec3 beam, inout float flux) {
    vec3 e = vec3(0.0);
    for (uint l = first; l < end; ++l) {
        vec3 wi, irradiance;
        light_incidence(lights[l], p, wi, irradiance);
        float cos_i = dot(n, wi);
        if (cos_i <= 0.0) continue;
        float v = sample_visibility(lights[l], p, n, wi, face);
        vec3 t = irradiance * (cos_i * dipole_fresnel_transmittance(cos_i, eta) * v);
        e += t;
        flux += t.r + t.g + t.b;
        float cos_t = sqrt(max(1.0 - (1.0 - cos_i * cos_i) / (eta * eta), 0.0));
        beam += (t.r + t.g + t.b) * (-(wi - n * cos_i) / eta - n * cos_t);
    }
    return e;
}

void main() {
    if (gl_GlobalInvocationID.x >= push.sample_count) return;
    uint i = push.first_sample + gl_GlobalInvocationID.x;
    SampleRecord s = samples[i];
    ObjectRecord o = objects[push.object];
    vec3 p = s.position_area.xyz;
    vec3 n = s.normal;
    vec3 face = unpack_octahedral(s.face_normal);
    vec3 environment;
    if (push.environment_kept != 0u) {
        environment = kept_environment[i].xyz;
    } else {
        vec3 unused = vec3(0.0);
        float unused_flux = 0.0;
        environment = transmitted(push.key_light_count, push.light_count, p, n, face, o.eta, unused, unused_flux);
        kept_environment[i] = vec4(environment, 0.0);
    }
    vec3 weighted = vec3(0.0);
    float key_flux = 0.0;
    uint key_lights = SPLAT_KEY_LIGHTS > 0u ? SPLAT_KEY_LIGHTS : push.key_light_count;
    vec3 e = transmitted(0u, key_lights, p, n, face, o.eta, weighted, key_flux) + environment;
    // The direction unit, its length in w: the transport kernel's entry basis reads the sum
    // itself (transport.comp), the between-points single scattering the direction.
    // Through its largest component: a light bright enough that the sum's square overflows
    // (past about 1e19) keeps its direction and length.
    float big = max(max(abs(weighted.x), abs(weighted.y)), abs(weighted.z));
    vec3 unit = big > 0.0 && !isinf(big) ? weighted / big : vec3(0.0);
    float unit_length = length(unit);
    vec4 beam = unit_length > 0.0 ? vec4(unit / unit_length, big * unit_length) : vec4(-n, 0.0);
    float area = s.position_area.w;
    if (push.environment_kept != 0u) {
        // The near energy depends on the sample's area and material alone, and whatever
        // changes those also splats the environment anew: it is the one written before, and
        // six Taylor remainders a sample (30 exponentials) are left out of a key light's frame.
        splat[i].irradiance_area = vec4(e, area);
        splat[i].near_energy.w = key_flux;
        splat[i].beam = beam;
        return;
    }
    float b = DIPOLE_B_PER_SQRT_AREA * sqrt(area);
    vec3 near_energy;
    for (int c = 0; c < 3; ++c) {
        near_energy[c] = dipole_near_energy(o.dipole[c], b);
    }
    splat[i] = SplatRecord(vec4(e, area), vec4(near_energy, key_flux), beam);
}

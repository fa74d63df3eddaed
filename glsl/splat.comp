#version 450
// Irradiance splat: for every sample point, the irradiance transmitted into the medium from
// every light: sum over lights of E_light cos(theta_i) F_t(cos theta_i, eta) V, with V from the
// light's shadow map (one bilinear compare tap: the sharpest, closest to ray casting). Also the sample's near-field energy per channel
// (dipole_near_energy), which depends only on its area and material, so that the gather pays
// for it once per sample instead of once per pair.
//
// Bindings: 0 = samples (SampleRecord[], read), 1 = objects (ObjectRecord[], read),
// 2 = lights (Light[], read), 3 = shadow maps (sampler2DArrayShadow),
// 4 = splat output (SplatRecord[]), write.
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
struct SplatPush {
    uint first_sample;      // one dispatch per object: its samples
    uint sample_count;
    uint light_count;
};
layout(push_constant) uniform SplatPushBlock { SplatPush push; };

void main() {
    if (gl_GlobalInvocationID.x >= push.sample_count) return;
    uint i = push.first_sample + gl_GlobalInvocationID.x;
    SampleRecord s = samples[i];
    ObjectRecord o = objects[uint(s.normal_object.w)];
    vec3 p = s.position_area.xyz;
    vec3 n = s.normal_object.xyz;
    float eta = o.eta;
    vec3 e = vec3(0.0);
    for (uint l = 0u; l < push.light_count; ++l) {
        vec3 wi, irradiance;
        light_incidence(lights[l], p, wi, irradiance);
        float cos_i = dot(n, wi);
        if (cos_i <= 0.0) continue;
        float v = light_visibility(lights[l], shadow_maps, p, n, 0);
        e += irradiance * (cos_i * dipole_fresnel_transmittance(cos_i, eta) * v);
    }
    float area = s.position_area.w;
    float b = DIPOLE_B_PER_SQRT_AREA * sqrt(area);
    vec3 near_energy;
    for (int c = 0; c < 3; ++c) {
        near_energy[c] = dipole_near_energy(o.dipole[c], b);
    }
    splat[i] = SplatRecord(vec4(e, area), vec4(near_energy, 0.0));
}

#version 450
// The benchmark's yardstick (benches/render.rs), not a renderer pass: the seed's discrete sum
// in its plainest form, M(x) = sum_i E_i R_d(|x - x_i|) A_i with the point kernel of Jensen et
// al. 2001 (seed Eq. 8) per channel, one receiver vertex per invocation, every sample read from
// its buffer, a plain f32 sum. It has no near field, so its answer is wrong where the sample
// spacing is not small next to the diffusion length; it only says how fast a pair can be.
//
// Bindings: 0 = vertices (VertexRecord[]), 1 = samples (SampleRecord[]), 2 = splat
// (SplatRecord[]), 3 = objects (ObjectRecord[]), 4 = exitance (vec4 per vertex, write).
#include "dipole.glsl"
#include "scene.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Exitance { vec4 exitance[]; };
struct GatherNaivePush {
    uint object;
};
layout(push_constant) uniform GatherNaivePushBlock { GatherNaivePush push; };

void main() {
    ObjectRecord o = objects[push.object];
    uint v = gl_GlobalInvocationID.x;
    if (v >= o.ranges.y) return;
    vec3 x = vertex_position(vertices[o.ranges.x + v]);
    vec3 sum = vec3(0.0);
    for (uint i = o.ranges.z; i < o.ranges.z + o.ranges.w; ++i) {
        vec4 pa = samples[i].position_area;
        float r = distance(x, pa.xyz);
        vec3 e = splat[i].irradiance_area.rgb;
        for (int c = 0; c < 3; ++c) {
            sum[c] += e[c] * dipole_r_d(o.dipole[c], r) * pa.w;
        }
    }
    exitance[o.ranges.x + v] = vec4(sum, 1.0);
}

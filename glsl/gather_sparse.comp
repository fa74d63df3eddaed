#version 450
// Sparse gather, for `render.gather = "sparse"`: the dipole sum evaluated only at the sample
// points, then blended to the vertices. Two stages, one dispatch each (push `stage`):
//   0: at every sample j, T_j = sum_i E_i far_kernel(|x_j - x_i|, A_i) + E_j E_near,j, the
//      exitance there (glsl/common/gather.glsl's far sum plus the sample's own near exitance);
//   1: at every vertex, M(x) = sum_j phi_j(x) T_j / sum_j phi_j(x) with the near-field Shepard
//      weights (nearest sample where none reaches).
// The far part is smooth on the scale of the sample spacing (optics::kernel), so sampling it at
// the samples loses little, and the per-vertex work drops from two exponentials per channel
// and pair to one weight per pair. Under uniform light every vertex still gets E R_d,total.
//
// Bindings: 0 = vertices (VertexRecord[]), 1 = samples (SampleRecord[]), 2 = splat
// (SplatRecord[]), 3 = objects (ObjectRecord[]), 4 = sample exitance (vec4 per sample,
// written by stage 0, read by stage 1), 5 = exitance (vec4 per vertex, written by stage 1).
// Push: GatherSparsePush.
#include "dipole.glsl"
#include "scene.glsl"
#include "gather.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 4) buffer SampleExitance { vec4 sample_exitance[]; };
layout(std430, set = 0, binding = 5) writeonly buffer Exitance { vec4 exitance[]; };
struct GatherSparsePush {
    uint object;            // the receiving object's index
    uint stage;             // 0: exitance at the samples; 1: blended to the vertices
};
layout(push_constant) uniform GatherSparsePushBlock { GatherSparsePush push; };

void main() {
    ObjectRecord o = objects[push.object];
    uint first_sample = o.ranges.z, sample_count = o.ranges.w;
    uint k = gl_GlobalInvocationID.x;
    if (push.stage == 0u) {
        if (k >= sample_count) return;
        uint j = first_sample + k;
        vec3 x = samples[j].position_area.xyz;
        DipoleChannel ch[3] = gather_channels(o);
        GatherSum g = gather_begin();
        for (uint i = first_sample; i < first_sample + sample_count; ++i) {
            gather_add(g, ch, x, samples[i].position_area, splat[i].irradiance_area.rgb, vec3(0.0));
            if (((i - first_sample) & 63u) == 63u) gather_flush(g);
        }
        gather_flush(g);
        sample_exitance[j] = vec4(max(g.far, vec3(0.0)) + splat[j].irradiance_area.rgb * splat[j].near_energy.rgb, 0.0);
        return;
    }
    if (k >= o.ranges.y) return;
    uint v = o.ranges.x + k;
    vec3 x = vertex_position(vertices[v]);
    vec3 sum = vec3(0.0);
    float weight_sum = 0.0;
    float nearest_r = 3.4e38;
    vec3 nearest = vec3(0.0);
    for (uint i = first_sample; i < first_sample + sample_count; ++i) {
        vec4 pa = samples[i].position_area;
        float r = distance(x, pa.xyz);
        float w = dipole_near_blend_weight(r, pa.w);
        vec3 t = sample_exitance[i].rgb;
        sum += w * t;
        weight_sum += w;
        if (r < nearest_r) {
            nearest_r = r;
            nearest = t;
        }
    }
    exitance[v] = vec4(weight_sum > 0.0 ? sum / weight_sum : nearest, 1.0);
}

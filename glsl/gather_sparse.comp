#version 450
// Sparse gather, for `render.gather = "sparse"`: the dipole sum evaluated only at the sample
// points, then blended to the vertices. Two stages, one dispatch each (push `stage`):
//   0: at every sample j, F_j = sum_i E_i far_kernel(|x_j - x_i|, A_i), the far part of the
//      exitance there (glsl/common/gather.glsl's far sum);
//   1: at every vertex, M(x) = sum_j phi_j(x) (F_j + k(x) E_j E_near,j) / sum_j phi_j(x) with the
//      near-field Shepard weights (nearest sample where none reaches), k(x) the share of the near
//      field kept beside open boundaries (gather_near_kept), as the vertex gather takes it. Vertices come in receiver groups
//      (sampling::ReceiverGroups, one workgroup each), and each group visits only the samples
//      whose blend radius reaches its bounding sphere (blend items, found on the CPU by
//      SampleTree::within_reach), staged through shared memory; the nearest-sample fallback
//      walks the sample hierarchy (glsl/common/tree.glsl).
// The far part is smooth on the scale of the sample spacing (optics::kernel), so sampling it at
// the samples loses little, and the per-vertex work drops from two exponentials per channel
// and pair to one weight per pair. Under uniform light every vertex still gets E R_d,total.
//
// Bindings: 0 = vertices (VertexRecord[]), 1 = samples (SampleRecord[]), 2 = splat
// (SplatRecord[]), 3 = objects (ObjectRecord[]), 4 = sample exitance (vec4 per sample,
// written by stage 0, read by stage 1), 5 = exitance (vec4 per vertex, written by stage 1),
// 6 = tree nodes (TreeNodeRecord[]), 7 = tree order (uint[]), 8 = receiver order (uint[]),
// 9 = receiver groups (ReceiverGroupRecord[]), 10 = blend items (uint[]), 11 = boundary
// distances (vec2 per vertex, mesh::Mesh::boundary_distances). Push: GatherSparsePush.
#include "dipole.glsl"
#include "scene.glsl"
#define GATHER_TRACK_NEAREST
#include "gather.glsl"

#define TILE 8u
layout(local_size_x = 8) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 4) buffer SampleExitance { vec4 sample_exitance[]; };
layout(std430, set = 0, binding = 5) writeonly buffer Exitance { vec4 exitance[]; };
layout(std430, set = 0, binding = 6) readonly buffer TreeNodes { TreeNodeRecord tree_nodes[]; };
layout(std430, set = 0, binding = 7) readonly buffer TreeOrder { uint tree_order[]; };
layout(std430, set = 0, binding = 8) readonly buffer ReceiverOrder { uint receiver_order[]; };
layout(std430, set = 0, binding = 9) readonly buffer ReceiverGroups { ReceiverGroupRecord receiver_groups[]; };
layout(std430, set = 0, binding = 10) readonly buffer BlendItems { uint blend_items[]; };
layout(std430, set = 0, binding = 11) readonly buffer VertexBoundary { vec2 vertex_boundary[]; };
struct GatherSparsePush {
    uint object;            // the receiving object's index
    uint stage;             // 0: exitance at the samples; 1: blended to the vertices
    uint first_node;        // the object's root in tree_nodes
    uint node_count;        // its node count
    uint first_receiver;    // its first entry in receiver_order
    uint first_group;       // its first group in receiver_groups
    uint receiver_count;    // receivers at the level of detail gathered (stage 1's threads)
    uint first_listed;      // unused here (the hierarchical gather's stage 0 lists its nodes)
    uint listed_count;
    uint only_picked;       // unused here (the hierarchical gather's pick of receivers)
};
layout(push_constant) uniform GatherSparsePushBlock { GatherSparsePush push; };

#include "tree.glsl"

shared vec4 tile_position_area[TILE];
shared vec4 tile_exitance[TILE];
shared vec4 tile_near[TILE];

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
        // Only the far sum is kept here (no near energy is passed), so the blend radius is moot.
        for (uint i = first_sample; i < first_sample + sample_count; ++i) {
            gather_add(g, ch, vec3(1.0), x, samples[i].position_area, splat[i].irradiance_area.rgb, vec3(0.0));
            if (((i - first_sample) & 63u) == 63u) gather_flush(g);
        }
        gather_flush(g);
        sample_exitance[j] = vec4(max(g.far, vec3(0.0)), 0.0);
        return;
    }
    uint count = push.receiver_count;
    bool is_receiver = k < count;
    uint v = receiver_order[push.first_receiver + min(k, max(count, 1u) - 1u)];
    vec3 x = vertex_position(vertices[v]);
    uvec4 list = receiver_groups[push.first_group + gl_WorkGroupID.x].blend;
    uint local = gl_LocalInvocationID.x;
    vec3 sum = vec3(0.0), near_sum = vec3(0.0);
    float weight_sum = 0.0, area_sum = 0.0;
    for (uint base = 0u; base < list.y; base += TILE) {
        uint j = base + local;
        if (j < list.y) {
            uint s = blend_items[list.x + j];
            tile_position_area[local] = samples[s].position_area;
            tile_exitance[local] = sample_exitance[s];
            tile_near[local] = vec4(splat[s].irradiance_area.rgb * splat[s].near_energy.rgb, 0.0);
        }
        barrier();
        uint n = min(TILE, list.y - base);
        for (uint t = 0u; t < n; ++t) {
            vec4 pa = tile_position_area[t];
            float w = dipole_near_blend_weight(distance(x, pa.xyz), pa.w, DIPOLE_NEAR_BLEND_RADIUS);
            sum += w * tile_exitance[t].rgb;
            near_sum += w * tile_near[t].rgb;
            weight_sum += w;
            area_sum += w * pa.w;
        }
        barrier();
    }
    if (!is_receiver) return;
    vec3 blended = vec3(0.0);
    if (weight_sum > 0.0) {
        vec3 kept = gather_near_kept(gather_channels(o), vec3(area_sum / weight_sum), vertex_boundary[v]);
        blended = (sum + near_sum * kept) / weight_sum;
    } else if (push.node_count > 0u) {
        uint s = tree_nearest_sample(x, push.first_node, push.node_count);
        blended = sample_exitance[s].rgb + splat[s].irradiance_area.rgb * splat[s].near_energy.rgb;
    }
    exitance[v] = vec4(blended, 1.0);
}

#version 450
// Hierarchical dipole gather, for `render.gather = "hierarchical"` (after Jensen and Buhler
// 2002): the vertex gather's sum with far clusters of samples standing in for their members.
// Which clusters stand in for which receivers is decided once on the CPU, per group of 8
// (RECEIVER_GROUP_SIZE) nearby vertices (sampling::SampleTree::cut, with the solid-angle bound
// render.gather_epsilon): each group has a list of items, samples and nodes. Two stages, one dispatch each (push
// `stage`):
//   0: per node of the object's hierarchy, its transmitted power sum E_i A_i per channel, its
//      power-weighted centroid and the power-weighted covariance of its members about it, from
//      this frame's splat;
//   1: one workgroup per receiver group, one invocation per vertex (in group order,
//      receiver_order), summing the group's items with gather.comp's tiled loop: first its
//      nodes, each its power times the cluster kernel (dipole_r_d_far_cluster_sq: R_far at the
//      centroid with b of the members' mean area, plus the second-order term of their spread),
//      then its samples as gather.comp sums them. Nodes lie beyond every near-blend radius, so
//      they add no Shepard weight. Where no weight reaches a vertex, the nearest sample's near
//      exitance is found by walking the hierarchy (glsl/common/tree.glsl).
// With epsilon = 0 every list holds every sample: the flat sum.
//
// Bindings: 0 = vertices (VertexRecord[]), 1 = samples (SampleRecord[]), 2 = splat
// (SplatRecord[]), 3 = objects (ObjectRecord[]), 4 = tree nodes (TreeNodeRecord[]), 5 = tree
// order (uint[]), 6 = node power (NodePowerRecord[], written by stage 0, read by stage 1),
// 7 = receiver order (uint[]), 8 = receiver groups (ReceiverGroupRecord[]), 9 = group items
// (uint[]), 10 = exitance (vec4 per vertex, written by stage 1), 11 = boundary distances (vec2
// per vertex, mesh::Mesh::boundary_distances). Push: GatherTreePush.
#include "dipole.glsl"
#include "scene.glsl"
#include "gather.glsl"

#define TILE 8u
layout(local_size_x = 8) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 4) readonly buffer TreeNodes { TreeNodeRecord tree_nodes[]; };
layout(std430, set = 0, binding = 5) readonly buffer TreeOrder { uint tree_order[]; };
layout(std430, set = 0, binding = 6) buffer NodePower { NodePowerRecord node_power[]; };
layout(std430, set = 0, binding = 7) readonly buffer ReceiverOrder { uint receiver_order[]; };
layout(std430, set = 0, binding = 8) readonly buffer ReceiverGroups { ReceiverGroupRecord receiver_groups[]; };
layout(std430, set = 0, binding = 9) readonly buffer GroupItems { uint group_items[]; };
layout(std430, set = 0, binding = 10) writeonly buffer Exitance { vec4 exitance[]; };
layout(std430, set = 0, binding = 11) readonly buffer VertexBoundary { vec2 vertex_boundary[]; };
struct GatherTreePush {
    uint object;            // the receiving object's index
    uint stage;             // 0: aggregate the nodes; 1: gather at the vertices
    uint first_node;        // the object's root in tree_nodes
    uint node_count;        // its node count
    uint first_receiver;    // its first entry in receiver_order
    uint first_group;       // its first group in receiver_groups
    uint receiver_count;    // receivers at the level of detail gathered (stage 1's threads)
};
layout(push_constant) uniform GatherTreePushBlock { GatherTreePush push; };

#include "tree.glsl"

// Per tile entry: a sample's position and area, irradiance and near energy; or a node's
// centroid and mean area, power, covariance diagonal (in the near-energy slot) and off-diagonal.
shared vec4 tile_position_area[TILE];
shared vec4 tile_irradiance[TILE];
shared vec4 tile_near_energy[TILE];
shared vec4 tile_cov_off[TILE];

void aggregate(uint i) {
    TreeNodeRecord n = tree_nodes[i];
    vec3 center = n.center_radius.xyz;
    vec3 power = vec3(0.0), offset = vec3(0.0), diag = vec3(0.0), off = vec3(0.0);
    float weight = 0.0;
    for (uint e = n.range_skip.x; e < n.range_skip.x + n.range_skip.y; ++e) {
        uint s = tree_order[e];
        vec4 ea = splat[s].irradiance_area;
        vec3 p = ea.rgb * ea.w;
        float w = p.r + p.g + p.b;
        power += p;
        // Relative to the node's centre, so that far-off objects keep their digits.
        vec3 y = samples[s].position_area.xyz - center;
        offset += w * y;
        diag += w * y * y;
        off += w * vec3(y.x * y.y, y.x * y.z, y.y * y.z);
        weight += w;
    }
    vec3 m = weight > 0.0 ? offset / weight : vec3(0.0);
    // Covariance about the centroid: E[y y^T] - m m^T, never negative on the diagonal.
    vec3 cov_diag = weight > 0.0 ? max(diag / weight - m * m, vec3(0.0)) : vec3(0.0);
    vec3 cov_off = weight > 0.0 ? off / weight - vec3(m.x * m.y, m.x * m.z, m.y * m.z) : vec3(0.0);
    node_power[i] = NodePowerRecord(vec4(power, 0.0), vec4(center + m, weight), vec4(cov_diag, 0.0), vec4(cov_off, 0.0));
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (push.stage == 0u) {
        if (k < push.node_count) aggregate(push.first_node + k);
        return;
    }
    ObjectRecord o = objects[push.object];
    uint count = push.receiver_count;
    bool is_receiver = k < count;
    uint v = receiver_order[push.first_receiver + min(k, max(count, 1u) - 1u)];
    vec3 x = vertex_position(vertices[v]);
    uvec4 list = receiver_groups[push.first_group + gl_WorkGroupID.x].items;
    uint local = gl_LocalInvocationID.x;
    DipoleChannel ch[3] = gather_channels(o);
    GatherSum g = gather_begin();
    // The group's nodes: power P per channel times the cluster kernel.
    for (uint base = 0u; base < list.y; base += TILE) {
        uint j = base + local;
        if (j < list.y) {
            uint node = group_items[list.x + j] & ~NODE_ITEM;
            NodePowerRecord p = node_power[node];
            tile_position_area[local] = vec4(p.mean_weight.xyz, tree_nodes[node].area_reach.z);
            tile_irradiance[local] = p.power;
            tile_near_energy[local] = p.cov_diag;
            tile_cov_off[local] = p.cov_off;
        }
        barrier();
        uint n = min(TILE, list.y - base);
        if (is_receiver) {
            for (uint t = 0u; t < n; ++t) {
                vec3 u = x - tile_position_area[t].xyz;
                float r_sq = dot(u, u);
                vec3 w = u * inversesqrt(max(r_sq, 1e-30)); // unit, so nothing of order r^4 forms
                vec3 cd = tile_near_energy[t].xyz, co = tile_cov_off[t].xyz;
                float tr_cov = cd.x + cd.y + cd.z;
                float axial_cov = dot(w * w, cd) + 2.0 * (w.x * w.y * co.x + w.x * w.z * co.y + w.y * w.z * co.z);
                float beta = DIPOLE_B_PER_SQRT_AREA * DIPOLE_B_PER_SQRT_AREA * tile_position_area[t].w;
                vec3 power = tile_irradiance[t].rgb;
                for (int c = 0; c < 3; ++c) {
                    g.partial[c] += power[c] * dipole_r_d_far_cluster_sq(ch[c], r_sq, beta, tr_cov, axial_cov);
                }
            }
            gather_flush(g);
        }
        barrier();
    }
    // Its samples, as gather.comp sums them.
    uint first_sample = list.x + list.y;
    for (uint base = 0u; base < list.z; base += TILE) {
        uint j = base + local;
        if (j < list.z) {
            uint s = group_items[first_sample + j];
            tile_position_area[local] = samples[s].position_area;
            tile_irradiance[local] = splat[s].irradiance_area;
            tile_near_energy[local] = splat[s].near_energy;
        }
        barrier();
        uint n = min(TILE, list.z - base);
        if (is_receiver) {
            for (uint t = 0u; t < n; ++t) {
                gather_add(g, ch, o.near_blend.rgb, x, tile_position_area[t], tile_irradiance[t].rgb, tile_near_energy[t].rgb);
            }
            gather_flush(g);
        }
        barrier();
    }
    if (!is_receiver) return;
    if (any(equal(g.weight_sum, vec3(0.0))) && push.node_count > 0u) {
        // No Shepard weight reached x: the nearest sample's near exitance, found anywhere in the
        // hierarchy (a node item may hold it), as the flat gather takes it.
        uint s = tree_nearest_sample(x, push.first_node, push.node_count);
        g.nearest_near = splat[s].irradiance_area.rgb * splat[s].near_energy.rgb;
    }
    exitance[v] = vec4(gather_end(g, ch, vertex_boundary[v]), 1.0);
}

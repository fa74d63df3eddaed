#version 450
// Hierarchical dipole gather, for `render.gather = "hierarchical"` (after Jensen and Buhler
// 2002): the vertex gather's sum with far clusters of samples standing in for their members.
// Which clusters stand in for which receiver is decided once on the CPU, for each receiver on
// its own (sampling::SampleTree::cut about its point, with the solid-angle bound
// render.gather_epsilon): each receiver has a list of items, nodes then samples, in the
// receiver-group records (one record per receiver here). Two stages, one dispatch each (push
// `stage`):
//   0: per node of the object's hierarchy, its transmitted power sum E_i A_i per channel, its
//      power-weighted centroid and the power-weighted covariance of its members about it, from
//      this frame's splat: a leaf from its samples, an inner node from its two children's
//      (the parallel-axis theorem), one height of the hierarchy per dispatch, leaves first
//      (GpuScene::node_heights), so each sample is read once rather than once per ancestor;
//   1: one invocation per vertex (in group order, receiver_order, so that the 8 lanes of a
//      workgroup walk similar lists), summing its own items straight from their buffers: first
//      its nodes, each its power times the cluster kernel (dipole_r_d_far_cluster_sq: R_far at
//      the centroid with b of the members' mean area, plus the second-order term of their
//      spread), then its samples as gather.comp sums them, flushing the Kahan sum every TILE
//      items. Nodes lie beyond every near-blend radius, so they add no Shepard weight. Where no
//      weight reaches a vertex, the nearest sample's near exitance is found by walking the
//      hierarchy (glsl/common/tree.glsl). A list per receiver rather than per group of 8: a
//      group's lists every sample within reach of any of its receivers one by one, three times
//      what one receiver needs on a coarse level (docs/STUDY.md, "What a group's list costs").
// With epsilon = 0 every list holds every sample: the flat sum.
//
// Bindings: 0 = vertices (VertexRecord[]), 1 = samples (SampleRecord[]), 2 = splat
// (SplatRecord[]), 3 = objects (ObjectRecord[]), 4 = tree nodes (TreeNodeRecord[]), 5 = tree
// order (uint[]), 6 = node power (NodePowerRecord[], written by stage 0, read by stage 1),
// 7 = receiver order (uint[]), 8 = receiver records (ReceiverGroupRecord[], one per receiver), 9 = group items
// (uint[]), 10 = exitance (vec4 per vertex, written by stage 1), 11 = boundary distances (vec2
// per vertex, mesh::Mesh::boundary_distances), 12 = receiver state (uvec2 per vertex, bit 0 of
// y picked to gather by glsl/receiver_view.comp where push.only_picked). Push: GatherTreePush.
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
layout(std430, set = 0, binding = 12) readonly buffer ReceiverState { uvec2 receiver_state[]; };
struct GatherTreePush {
    uint object;            // the receiving object's index
    uint stage;             // 0: aggregate the nodes; 1: gather at the vertices
    uint first_node;        // the object's root in tree_nodes
    uint node_count;        // its node count
    uint first_receiver;    // its first entry in receiver_order
    uint first_group;       // its first receiver's record in receiver_groups
    uint receiver_count;    // receivers at the level of detail gathered (stage 1's threads)
    uint first_listed;      // stage 0: this dispatch's nodes, tree_order[first_listed + k]
    uint listed_count;      // stage 0: their count (one height of the hierarchy)
    uint only_picked;       // stage 1: only the receivers glsl/receiver_view.comp picked
};
layout(push_constant) uniform GatherTreePushBlock { GatherTreePush push; };

#include "tree.glsl"

// Node i from its children l and r (already aggregated): powers add; the centroid is the
// weighted mean of theirs; the covariance about it is each child's plus the outer product of its
// centroid's offset (the parallel-axis theorem), weighted. Offsets are taken from the node's
// centre, as a leaf's are, so that far-off objects keep their digits.
void combine(uint i, uint l, uint r) {
    vec3 center = tree_nodes[i].center_radius.xyz;
    NodePowerRecord a = node_power[l], b = node_power[r];
    float wa = a.mean_weight.w, wb = b.mean_weight.w, w = wa + wb;
    vec3 power = a.power.rgb + b.power.rgb;
    if (!(w > 0.0)) {
        node_power[i] = NodePowerRecord(vec4(power, tree_nodes[i].area_reach.z), vec4(center, 0.0), vec4(0.0), vec4(0.0));
        return;
    }
    vec3 ya = a.mean_weight.xyz - center, yb = b.mean_weight.xyz - center;
    vec3 m = (wa * ya + wb * yb) / w;
    vec3 da = ya - m, db = yb - m;
    vec3 diag = (wa * (a.cov_diag.xyz + da * da) + wb * (b.cov_diag.xyz + db * db)) / w;
    vec3 off = (wa * (a.cov_off.xyz + vec3(da.x * da.y, da.x * da.z, da.y * da.z))
                + wb * (b.cov_off.xyz + vec3(db.x * db.y, db.x * db.z, db.y * db.z))) / w;
    node_power[i] = NodePowerRecord(vec4(power, tree_nodes[i].area_reach.z), vec4(center + m, w), vec4(max(diag, vec3(0.0)), 0.0), vec4(off, 0.0));
}

void aggregate(uint i) {
    TreeNodeRecord n = tree_nodes[i];
    if (n.range_skip.w == 0u) {
        combine(i, i + 1u, tree_nodes[i + 1u].range_skip.z);
        return;
    }
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
    node_power[i] = NodePowerRecord(vec4(power, n.area_reach.z), vec4(center + m, weight), vec4(cov_diag, 0.0), vec4(cov_off, 0.0));
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (push.stage == 0u) {
        if (k < push.listed_count) aggregate(tree_order[push.first_listed + k]);
        return;
    }
    // No barrier below, so invocations past the last receiver may leave at once.
    if (k >= push.receiver_count) return;
    uint v = receiver_order[push.first_receiver + k];
    // The rest hold exitance gathered under this generation of the splat, or wait their turn;
    // they leave before the object's record is loaded.
    if (push.only_picked != 0u && (receiver_state[v].y & 1u) == 0u) return;
    ObjectRecord o = objects[push.object];
    vec3 x = vertex_position(vertices[v]);
    uvec4 list = receiver_groups[push.first_group + k].items;
    DipoleChannel ch[3] = gather_channels(o);
    GatherSum g = gather_begin();
    // The receiver's nodes: power P per channel times the cluster kernel, flushed every TILE.
    for (uint base = 0u; base < list.y; base += TILE) {
        uint n = min(TILE, list.y - base);
        for (uint t = 0u; t < n; ++t) {
            uint node = group_items[list.x + base + t] & ~NODE_ITEM;
            NodePowerRecord p = node_power[node];
            vec3 u = x - p.mean_weight.xyz;
            float r_sq = dot(u, u);
            vec3 w = u * inversesqrt(max(r_sq, 1e-30)); // unit, so nothing of order r^4 forms
            vec3 cd = p.cov_diag.xyz, co = p.cov_off.xyz;
            float tr_cov = cd.x + cd.y + cd.z;
            float axial_cov = dot(w * w, cd) + 2.0 * (w.x * w.y * co.x + w.x * w.z * co.y + w.y * w.z * co.z);
            // The members' mean area rides in the power record: one load per item, not two.
            float beta = DIPOLE_B_PER_SQRT_AREA * DIPOLE_B_PER_SQRT_AREA * p.power.w;
            vec3 power = p.power.rgb;
            for (int c = 0; c < 3; ++c) {
                g.partial[c] += power[c] * dipole_r_d_far_cluster_sq(ch[c], r_sq, beta, tr_cov, axial_cov);
            }
        }
        gather_flush(g);
    }
    // Its samples, as gather.comp sums them.
    uint first_sample = list.x + list.y;
    for (uint base = 0u; base < list.z; base += TILE) {
        uint n = min(TILE, list.z - base);
        for (uint t = 0u; t < n; ++t) {
            uint s = group_items[first_sample + base + t];
            gather_add(g, ch, o.near_blend.rgb, x, samples[s].position_area, splat[s].irradiance_area.rgb, splat[s].near_energy.rgb);
        }
        gather_flush(g);
    }
    if (any(equal(g.weight_sum, vec3(0.0))) && push.node_count > 0u) {
        // No Shepard weight reached x: the nearest sample's near exitance, found anywhere in the
        // hierarchy (a node item may hold it), as the flat gather takes it.
        uint s = tree_nearest_sample(x, push.first_node, push.node_count);
        g.nearest_near = splat[s].irradiance_area.rgb * splat[s].near_energy.rgb;
    }
    exitance[v] = vec4(gather_end(g, ch, vertex_boundary[v]), 1.0);
}

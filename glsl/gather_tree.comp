#version 450
// Hierarchical dipole gather, for `render.gather = "hierarchical"` (after Jensen and Buhler
// 2002): the vertex gather's sum with far clusters of samples standing in for their members.
// Two stages, one dispatch each (push `stage`):
//   0: per node of the object's sample hierarchy, its transmitted power sum E_i A_i per channel
//      and its power-weighted centroid, from this frame's splat;
//   1: per vertex, tree_gather (glsl/common/tree.glsl) with the solid-angle bound
//      push.epsilon; epsilon = 0 is the flat sum of gather.comp. Invocations take the object's
//      vertices in group order (receiver_order), one workgroup per group of 64, and walk the
//      hierarchy with the group's bounding sphere, so the walk is uniform across the workgroup.
//
// Bindings: 0 = vertices (VertexRecord[]), 1 = samples (SampleRecord[]), 2 = splat
// (SplatRecord[]), 3 = objects (ObjectRecord[]), 4 = tree nodes (TreeNodeRecord[]), 5 = tree
// order (uint[]), 6 = node power (NodePowerRecord[], written by stage 0, read by stage 1),
// 7 = receiver order (uint[]), 8 = receiver groups (vec4[]: centre, radius), 9 = exitance (vec4
// per vertex, written by stage 1). Push: GatherTreePush.
#include "dipole.glsl"
#include "scene.glsl"
#include "gather.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 4) readonly buffer TreeNodes { TreeNodeRecord tree_nodes[]; };
layout(std430, set = 0, binding = 5) readonly buffer TreeOrder { uint tree_order[]; };
layout(std430, set = 0, binding = 6) buffer NodePower { NodePowerRecord node_power[]; };
layout(std430, set = 0, binding = 7) readonly buffer ReceiverOrder { uint receiver_order[]; };
layout(std430, set = 0, binding = 8) readonly buffer ReceiverGroups { vec4 receiver_groups[]; };
layout(std430, set = 0, binding = 9) writeonly buffer Exitance { vec4 exitance[]; };
struct GatherTreePush {
    uint object;            // the receiving object's index
    uint stage;             // 0: aggregate the nodes; 1: gather at the vertices
    uint first_node;        // the object's root in tree_nodes
    uint node_count;        // its node count
    uint first_receiver;    // its first entry in receiver_order
    uint first_group;       // its first group in receiver_groups
    float epsilon;          // solid-angle bound: a node of area A at distance r is used whole when A < epsilon r^2
};
layout(push_constant) uniform GatherTreePushBlock { GatherTreePush push; };

#define TREE_GATHER
#include "tree.glsl"

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (push.stage == 0u) {
        if (k >= push.node_count) return;
        uint i = push.first_node + k;
        TreeNodeRecord n = tree_nodes[i];
        vec3 center = n.center_radius.xyz;
        vec3 power = vec3(0.0), offset = vec3(0.0);
        float weight = 0.0;
        for (uint e = n.range_skip.x; e < n.range_skip.x + n.range_skip.y; ++e) {
            uint s = tree_order[e];
            vec4 ea = splat[s].irradiance_area;
            vec3 p = ea.rgb * ea.w;
            float w = p.r + p.g + p.b;
            power += p;
            // Relative to the node's centre, so that far-off objects keep their digits.
            offset += w * (samples[s].position_area.xyz - center);
            weight += w;
        }
        vec3 mean = weight > 0.0 ? center + offset / weight : center;
        node_power[i] = NodePowerRecord(vec4(power, 0.0), vec4(mean, weight));
        return;
    }
    ObjectRecord o = objects[push.object];
    uint count = o.ranges.y;
    // Invocations past the end walk with their group (keeping the walk uniform) but write nothing.
    uint v = receiver_order[push.first_receiver + min(k, max(count, 1u) - 1u)];
    vec4 group = receiver_groups[push.first_group + gl_WorkGroupID.x];
    DipoleChannel ch[3] = gather_channels(o);
    GatherSum g = tree_gather(vertex_position(vertices[v]), group.xyz, group.w, ch, push.first_node, push.node_count,
                              push.epsilon);
    if (k < count) exitance[v] = vec4(gather_end(g), 1.0);
}

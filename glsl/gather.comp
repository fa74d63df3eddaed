#version 450
// Dipole gather (seed Eq. 11 with the near-field treatment of src/optics/kernel.rs): the radiant
// exitance at the receiver vertices of one translucent object (those its level of detail uses,
// listed in level_vertices), over that object's samples,
//     M(x) = sum_i E_i far_kernel(r_i, A_i) + sum_i phi_i E_i E_near,i / sum_i phi_i
// (kernel::far_kernel explains the split). Samples are staged through shared memory in tiles of 64 (one
// load per tile for the whole workgroup); each tile's far sum is added to a Kahan-compensated
// total per channel so that the f32 sum stays within 1e-3 of the f64 reference at any sample count.
//
// Where no Shepard weight reaches a vertex, the nearest sample's near exitance is found by
// walking the object's sample hierarchy (glsl/common/tree.glsl) rather than tracked per pair.
//
// Bindings: 0 = vertices (VertexRecord[], read), 1 = samples (SampleRecord[], read), 2 = splat
// (SplatRecord[], read), 3 = objects (ObjectRecord[], read), 4 = exitance (vec4 per vertex, write),
// 5 = tree nodes (TreeNodeRecord[]), 6 = tree order (uint[]), 7 = boundary distances (vec2 per
// vertex, mesh::Mesh::boundary_distances), 8 = level vertices (object-relative vertex indices,
// GpuScene::level_vertices). Push: GatherPush.
#include "dipole.glsl"
#include "scene.glsl"
#include "gather.glsl"

#define TILE 64u
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Exitance { vec4 exitance[]; };
layout(std430, set = 0, binding = 5) readonly buffer TreeNodes { TreeNodeRecord tree_nodes[]; };
layout(std430, set = 0, binding = 6) readonly buffer TreeOrder { uint tree_order[]; };
layout(std430, set = 0, binding = 7) readonly buffer VertexBoundary { vec2 vertex_boundary[]; };
layout(std430, set = 0, binding = 8) readonly buffer LevelVertices { uint level_vertices[]; };
struct GatherPush {
    uint object;            // the receiving object's index
    uint first_node;        // its root in tree_nodes
    uint node_count;        // its node count
    uint first_entry;       // its level's first entry in level_vertices
    uint receiver_count;    // the vertices its level uses
};
layout(push_constant) uniform GatherPushBlock { GatherPush push; };

#include "tree.glsl"

shared vec4 tile_position_area[TILE];
shared vec4 tile_irradiance[TILE];
shared vec4 tile_near_energy[TILE];

void main() {
    ObjectRecord o = objects[push.object];
    uint first_vertex = o.ranges.x, receiver_count = push.receiver_count;
    uint first_sample = o.ranges.z, sample_count = o.ranges.w;
    uint local = gl_LocalInvocationID.x;
    bool is_receiver = gl_GlobalInvocationID.x < receiver_count;
    uint v = level_vertices[push.first_entry + min(gl_GlobalInvocationID.x, max(receiver_count, 1u) - 1u)];
    uint vi = first_vertex + v;
    vec3 x = vertex_position(vertices[vi]);
    DipoleChannel ch[3] = gather_channels(o);
    GatherSum g = gather_begin();
    for (uint base = 0u; base < sample_count; base += TILE) {
        uint j = base + local;
        if (j < sample_count) {
            uint s = first_sample + j;
            tile_position_area[local] = samples[s].position_area;
            tile_irradiance[local] = splat[s].irradiance_area;
            tile_near_energy[local] = splat[s].near_energy;
        }
        barrier();
        uint n = min(TILE, sample_count - base);
        if (is_receiver) {
            for (uint k = 0u; k < n; ++k) {
                gather_add(g, ch, o.near_blend.rgb, x, tile_position_area[k], tile_irradiance[k].rgb, tile_near_energy[k].rgb);
            }
            gather_flush(g);
        }
        barrier();
    }
    if (!is_receiver) return;
    if (any(equal(g.weight_sum, vec3(0.0))) && push.node_count > 0u) {
        uint s = tree_nearest_sample(x, push.first_node, push.node_count);
        g.nearest_near = splat[s].irradiance_area.rgb * splat[s].near_energy.rgb;
    }
    exitance[first_vertex + v] = vec4(gather_end(g, ch, vertex_boundary[vi]), 1.0);
}

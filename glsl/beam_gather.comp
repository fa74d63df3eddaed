#version 450
// Single scattering between points (Jensen et al. 2001, Eq. 3 resolved in space;
// src/optics/beam_single.rs): the radiant exitance of the channels a material's `model` gives
// to it, at the receiver vertices of one object (its level of detail this frame), over the
// object's samples within its reach:
//     M(x) = R1(1) sum_i A_i E_i T(rho_i, cos phi_i, mu_i) / sum_i A_i T(rho_i, 1, 1)
// with T the kernel tabulated on a plane and averaged over the samples' footprints
// (glsl/common/beam_table.glsl), rho_i the chord to sample i, phi_i the angle between the
// chord's and the beam's paths along the sample's tangent plane, mu_i the cosine of the
// sample's beam (SplatRecord::beam) with its inward normal. The quotient is the density
// correction (optics::beam_table's module doc): the same samples' sum at normal incidence
// against the half-space's exact R1(1), which takes out the aliasing of the kernel's peak.
// Samples are found by walking the object's hierarchy (glsl/common/tree.glsl), skipping nodes
// beyond the reach. Runs after the dipole gather and overwrites its value in these channels only.
//
// Bindings: 0 = vertices (VertexRecord[], read), 1 = samples (SampleRecord[], read), 2 = splat
// (SplatRecord[], read), 3 = objects (ObjectRecord[], read), 4 = exitance (vec4 per vertex,
// read and written), 5 = level vertices, 6 = the tables (vec4[]), 7 = tree nodes
// (TreeNodeRecord[]), 8 = tree order (uint[]), 9 = receiver order (uint[]). Push: BeamGatherPush.
#include "dipole.glsl"
#include "scene.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 4) buffer Exitance { vec4 exitance[]; };
layout(std430, set = 0, binding = 5) readonly buffer LevelVertices { uint level_vertices[]; };
layout(std430, set = 0, binding = 6) readonly buffer BeamTables { vec4 beam_tables[]; };
layout(std430, set = 0, binding = 7) readonly buffer TreeNodes { TreeNodeRecord tree_nodes[]; };
layout(std430, set = 0, binding = 8) readonly buffer TreeOrder { uint tree_order[]; };
layout(std430, set = 0, binding = 9) readonly buffer ReceiverOrder { uint receiver_order[]; };
struct BeamGatherPush {
    uvec4 object;           // x: the object; y: its receivers' first entry in level_vertices
                            // or receiver_order; z: their count; w: channel mask (bit c: channel c)
    uvec4 tree;             // x: its table's base in beam_tables; y: its root in tree_nodes;
                            // z: its node count; w: 1: the receivers are receiver_order's
                            // (absolute, grouped in space), 0: level_vertices' (object-relative)
    vec4 critical;          // x: the critical cosine inside; yzw: 0
    vec4 normal_total;      // xyz: R1(1) per channel; w: the reach (scene units)
};
layout(push_constant) uniform BeamGatherPushBlock { BeamGatherPush push; };

#include "beam_table.glsl"

// Sample s's terms at receiver x: A E T into `sum`, A T(rho, mu = 1) into `norm`.
void add_sample(uint s, vec3 x, inout vec3 sum, inout vec3 norm) {
    vec4 pa = samples[s].position_area;
    vec3 d = x - pa.xyz;
    float reach = push.normal_total.w;
    float dist_sq = dot(d, d);
    if (!(dist_sq < reach * reach)) return;
    vec3 nrm = samples[s].normal, w = splat[s].beam.xyz;
    float mu = clamp(-dot(w, nrm), 0.0, 1.0);
    vec3 dt = d - dot(d, nrm) * nrm, wt = w + mu * nrm;
    float len = length(dt) * length(wt);
    float cos_phi = len > 0.0 ? dot(dt, wt) / len : 1.0;
    // The table's x axis: sqrt(rho / reach), the same distance for every channel.
    float x_axis = sqrt(sqrt(dist_sq) / reach);
    uint table = push.tree.x;
    sum += pa.w * splat[s].irradiance_area.rgb * beam_table_lookup(table, push.critical.x, x_axis, cos_phi, mu);
    norm += pa.w * beam_table_normal(table, x_axis);
}

void main() {
    uint receiver_count = push.object.z, mask = push.object.w;
    if (gl_GlobalInvocationID.x >= receiver_count) return;
    ObjectRecord o = objects[push.object.x];
    uint entry = push.object.y + gl_GlobalInvocationID.x;
    // Neighbouring invocations walk nearly the same nodes when their receivers lie together.
    uint vi = push.tree.w != 0u ? receiver_order[entry] : o.ranges.x + level_vertices[entry];
    vec3 x = vertex_position(vertices[vi]);
    float reach = push.normal_total.w;
    vec3 sum = vec3(0.0), norm = vec3(0.0);
    uint i = push.tree.y, end = push.tree.y + push.tree.z;
    while (i < end) {
        TreeNodeRecord n = tree_nodes[i];
        if (distance(x, n.center_radius.xyz) - n.center_radius.w >= reach) {
            i = n.range_skip.z;
        } else if (n.range_skip.w != 0u) {
            for (uint k = n.range_skip.x; k < n.range_skip.x + n.range_skip.y; ++k) {
                add_sample(tree_order[k], x, sum, norm);
            }
            i = n.range_skip.z;
        } else {
            i += 1u;
        }
    }
    bvec3 on = bvec3((mask & 1u) != 0u, (mask & 2u) != 0u, (mask & 4u) != 0u);
    vec3 m = mix(vec3(0.0), push.normal_total.rgb * sum / max(norm, vec3(1e-30)), greaterThan(norm, vec3(0.0)));
    vec4 old = exitance[vi];
    exitance[vi] = vec4(mix(old.rgb, max(m, vec3(0.0)), on), old.w);
}

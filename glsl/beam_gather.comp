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
// against the half-space's exact R1(1), which takes out the aliasing of the kernel's peak. Its
// denominator depends on the geometry alone and is summed once on the CPU over the same walk
// (render::beam_gather::receiver_walks), so the pass sums only the lit terms.
// Samples are found by walking the object's hierarchy (glsl/common/tree.glsl), skipping nodes
// beyond the reach. A node whose radius is under render.beam_opening times its distance from x
// (or times the table's window radius, on whose scale the tabulated kernel is smooth, when x is
// nearer) stands in for its members: their summed A E at their area-weighted centroid, with their
// mean normal and their power-weighted mean beam. The walk depends on the geometry alone too:
// where render.beam_walk_mib allows, each vertex's was taken at upload and is read from
// beam_items (a step per source, no node tests); otherwise it is taken here each frame, skipping
// the nodes that transmit nothing in the model's channels. Two stages (push `stage.x`):
//   0: per node, its BeamNodeRecord from this frame's splat: a leaf from its samples (writing
//      each sample's BeamSourceRecord on the way, what stage 1 reads of it in one place), an
//      inner node from its two children's, one height of the hierarchy per dispatch, leaves
//      first; and the node's stand-in, as a BeamSourceRecord;
//   1: one dispatch, one invocation per receiver: the walk and the sum. Runs after the dipole
//      gather and overwrites its value in these channels only.
//
// Bindings: 0 = vertices (VertexRecord[], read), 1 = samples (SampleRecord[], read), 2 = splat
// (SplatRecord[], read), 3 = objects (ObjectRecord[], read), 4 = exitance (vec4 per vertex,
// read and written), 5 = level vertices, 6 = the tables (uvec4[], packed f16), 7 = tree nodes
// (TreeNodeRecord[]), 8 = tree order (uint[]), 9 = receiver order (uint[]), 10 = beam nodes
// (BeamNodeRecord[], written by stage 0, read by stage 1), 11 = beam sources (BeamSourceRecord
// per leaf-order entry, then per node its stand-in from entry push `stage.w`; written by stage
// 0, read by stage 1), 12 = per vertex and one more, BeamReceiverRecord (the density
// correction's denominator and the vertex's first walk item), 13 = the walks' items (uint[]:
// NODE_ITEM | a node, or a sample's leaf-order entry, both object-relative). Push:
// BeamGatherPush.
#include "dipole.glsl"
#include "scene.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 4) buffer Exitance { vec4 exitance[]; };
layout(std430, set = 0, binding = 5) readonly buffer LevelVertices { uint level_vertices[]; };
layout(std430, set = 0, binding = 6) readonly buffer BeamTables { uvec4 beam_tables[]; };
layout(std430, set = 0, binding = 7) readonly buffer TreeNodes { TreeNodeRecord tree_nodes[]; };
layout(std430, set = 0, binding = 8) readonly buffer TreeOrder { uint tree_order[]; };
layout(std430, set = 0, binding = 9) readonly buffer ReceiverOrder { uint receiver_order[]; };
layout(std430, set = 0, binding = 10) buffer BeamNodes { BeamNodeRecord beam_nodes[]; };
layout(std430, set = 0, binding = 11) buffer BeamSources { BeamSourceRecord beam_sources[]; };
layout(std430, set = 0, binding = 12) readonly buffer BeamNorms { BeamReceiverRecord beam_norms[]; };
layout(std430, set = 0, binding = 13) readonly buffer BeamItems { uint beam_items[]; };
struct BeamGatherPush {
    uvec4 object;           // x: the object; y: its receivers' first entry in level_vertices
                            // or receiver_order; z: their count; w: channel mask (bit c: channel c)
    uvec4 tree;             // x: its table's base in beam_tables; y: its root in tree_nodes;
                            // z: its node count; w: bit 0: the receivers are receiver_order's
                            // (absolute, grouped in space), else level_vertices' (object-
                            // relative); bit 1: their walks are read from beam_items, else taken
    vec4 critical;          // x: the critical cosine inside; y: render.beam_opening; z: the
                            // table's window radius (scene units); w: 0
    vec4 normal_total;      // xyz: R1(1) per channel; w: the reach (scene units)
    uvec4 stage;            // x: 0 aggregate the nodes, 1 gather; y, z: stage 0's nodes,
                            // tree_order[y + k] for k < z (one height); w: the nodes' stand-ins'
                            // first entry in beam_sources (tree_order's length)
};
layout(push_constant) uniform BeamGatherPushBlock { BeamGatherPush push; };

#include "beam_table.glsl"

const uint NO_TERM = 0xffffffffu;

// The terms of light entering at p (normal nrm, beam at cosine mu inside whose direction along
// the tangent plane is `along`, summed A E `power`) at receiver x: A E T into `sum`. cos phi is
// the angle between the chord's projection on the tangent plane and `along`.
void add_term(vec3 x, vec3 p, vec3 nrm, float mu, vec3 along, vec3 power, inout vec3 sum) {
    vec3 d = x - p;
    float reach = push.normal_total.w;
    float dist_sq = dot(d, d);
    if (!(dist_sq < reach * reach)) return;
    float dn = dot(d, nrm);
    float tangential = sqrt(max(dist_sq - dn * dn, 0.0));
    float cos_phi = tangential > 0.0 ? dot(d, along) / tangential : 1.0;
    // The table's x axis: sqrt(rho / reach), the same distance for every channel.
    float x_axis = sqrt(sqrt(dist_sq) / reach);
    uint table = push.tree.x;
    sum += power * beam_table_lookup(table, push.object.w, push.critical.x, x_axis, cos_phi, mu);
}

// The beam w's cosine with the inward normal and its unit direction along the tangent plane
// (any tangent where it is normal: the table does not depend on phi at mu = 1).
float beam_along(vec3 w, vec3 nrm, out vec3 along) {
    float mu = clamp(-dot(w, nrm), 0.0, 1.0);
    vec3 wt = w + mu * nrm;
    float len = length(wt);
    vec3 tangent = abs(nrm.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    along = len > 1e-6 ? wt / len : normalize(cross(nrm, tangent));
    return mu;
}

// The source at entry k of beam_sources: a sample (leaf-order entry k) or a node's stand-in.
void add_source(uint k, vec3 x, inout vec3 sum) {
    BeamSourceRecord r = beam_sources[k];
    if (!any(greaterThan(r.power_area.rgb, vec3(0.0)))) return;
    vec3 along = unpack_octahedral(floatBitsToUint(r.normal_along.w));
    add_term(x, r.position_mu.xyz, r.normal_along.xyz, r.position_mu.w, along, r.power_area.rgb, sum);
}

// The record of node i standing in for its members, from its BeamNodeRecord b: at their
// area-weighted centroid, with their unit mean normal and beam (the inward normal where no
// member is lit; its power is then 0). Written once per frame by stage 0 to the node's entry past
// the samples' (push `stage.w + i`), so that stage 1 reads a node as it reads a sample.
BeamSourceRecord stand_in(BeamNodeRecord b) {
    float nl = length(b.normal.xyz), bl = length(b.beam.xyz);
    vec3 nrm = nl > 0.0 ? b.normal.xyz / nl : vec3(0.0, 0.0, 1.0);
    vec3 along;
    float mu = beam_along(bl > 0.0 ? b.beam.xyz / bl : -nrm, nrm, along);
    return BeamSourceRecord(vec4(b.position.xyz, mu), b.power, vec4(nrm, uintBitsToFloat(pack_octahedral(along))));
}

// Stage 0: node i's record from its samples (a leaf) or its two children's.
void aggregate(uint i) {
    TreeNodeRecord n = tree_nodes[i];
    if (n.range_skip.w == 0u) {
        BeamNodeRecord l = beam_nodes[i + 1u], r = beam_nodes[tree_nodes[i + 1u].range_skip.z];
        float a = l.power.w + r.power.w;
        vec3 c = a > 0.0 ? (l.power.w * l.position.xyz + r.power.w * r.position.xyz) / a : n.center_radius.xyz;
        BeamNodeRecord b = BeamNodeRecord(l.power + r.power, vec4(c, l.position.w + r.position.w),
                                          l.normal + r.normal, l.beam + r.beam);
        beam_nodes[i] = b;
        beam_sources[push.stage.w + i] = stand_in(b);
        return;
    }
    vec4 power = vec4(0.0);
    vec3 offset = vec3(0.0), normal = vec3(0.0), beam = vec3(0.0);
    float weight = 0.0;
    for (uint e = n.range_skip.x; e < n.range_skip.x + n.range_skip.y; ++e) {
        uint s = tree_order[e];
        vec4 pa = samples[s].position_area;
        vec3 p = pa.w * splat[s].irradiance_area.rgb, nrm = samples[s].normal, w = splat[s].beam.xyz;
        power += vec4(p, pa.w);
        // Relative to the node's centre, so that far-off objects keep their digits.
        offset += pa.w * (pa.xyz - n.center_radius.xyz);
        normal += pa.w * nrm;
        beam += (p.r + p.g + p.b) * w;
        weight += p.r + p.g + p.b;
        vec3 along;
        float mu = beam_along(w, nrm, along);
        beam_sources[e] = BeamSourceRecord(vec4(pa.xyz, mu), vec4(p, pa.w), vec4(nrm, uintBitsToFloat(pack_octahedral(along))));
    }
    vec3 c = n.center_radius.xyz + (power.w > 0.0 ? offset / power.w : vec3(0.0));
    BeamNodeRecord b = BeamNodeRecord(power, vec4(c, weight), vec4(normal, 0.0), vec4(beam, 0.0));
    beam_nodes[i] = b;
    beam_sources[push.stage.w + i] = stand_in(b);
}

// The walk of the object's hierarchy about x, each frame: nodes beyond the reach or transmitting
// nothing in the model's channels (on) skipped, near enough ones standing in for their members.
void walk(vec3 x, bvec3 on, inout vec3 sum) {
    float reach = push.normal_total.w, opening = push.critical.y, window = push.critical.z;
    // One source summed per iteration at most, in one place: the invocations of a SIMD group
    // walk apart, and a CPU driver runs every branch any of them takes, so a leaf's loop or a
    // node's own term inside the walk's branches cost every invocation each time.
    uint i = push.tree.y, end = push.tree.y + push.tree.z;
    uint k = 0u, k_end = 0u;  // a leaf's members still to sum (leaf-order entries)
    while (k < k_end || i < end) {
        uint term = NO_TERM;
        if (k < k_end) {
            term = k++;
        } else {
            TreeNodeRecord n = tree_nodes[i];
            float dist = distance(x, n.center_radius.xyz);
            uint standin = push.stage.w + i;
            // Out of reach, or transmitting nothing in the model's channels (the denominator,
            // which every node within reach adds to, is summed once: BeamReceiverRecord).
            if (dist - n.center_radius.w >= reach || !(dot(vec3(on), beam_sources[standin].power_area.rgb) > 0.0)) {
                i = n.range_skip.z;
            } else if (n.center_radius.w < opening * max(dist, window)) {
                term = standin;
                i = n.range_skip.z;
            } else if (n.range_skip.w != 0u) {
                k = n.range_skip.x;
                k_end = k + n.range_skip.y;
                i = n.range_skip.z;
            } else {
                i += 1u;
            }
        }
        if (term != NO_TERM) add_source(term, x, sum);
    }
}

void main() {
    if (push.stage.x == 0u) {
        if (gl_GlobalInvocationID.x < push.stage.z) aggregate(tree_order[push.stage.y + gl_GlobalInvocationID.x]);
        return;
    }
    uint receiver_count = push.object.z, mask = push.object.w;
    if (gl_GlobalInvocationID.x >= receiver_count) return;
    ObjectRecord o = objects[push.object.x];
    uint entry = push.object.y + gl_GlobalInvocationID.x;
    // Neighbouring invocations walk nearly the same nodes when their receivers lie together.
    uint vi = (push.tree.w & 1u) != 0u ? receiver_order[entry] : o.ranges.x + level_vertices[entry];
    vec3 x = vertex_position(vertices[vi]);
    vec3 sum = vec3(0.0);
    bvec3 on = bvec3((mask & 1u) != 0u, (mask & 2u) != 0u, (mask & 4u) != 0u);
    if ((push.tree.w & 2u) != 0u) {
        // The walk read as it was taken at upload (render::beam_gather::receiver_walks): a
        // node as NODE_ITEM | its index, a sample as its leaf-order entry, both relative to the
        // object's. The nodes that transmit nothing are on it too; add_source passes them by.
        uint root = push.tree.y, first_entry = tree_nodes[root].range_skip.x;
        for (uint j = beam_norms[vi].first_item; j < beam_norms[vi + 1u].first_item; ++j) {
            uint item = beam_items[j];
            add_source((item & NODE_ITEM) != 0u ? push.stage.w + root + (item & ~NODE_ITEM) : first_entry + item, x, sum);
        }
    } else {
        walk(x, on, sum);
    }
    vec3 norm = beam_norms[vi].norm;
    vec3 m = mix(vec3(0.0), push.normal_total.rgb * sum / max(norm, vec3(1e-30)), greaterThan(norm, vec3(0.0)));
    vec4 old = exitance[vi];
    exitance[vi] = vec4(mix(old.rgb, max(m, vec3(0.0)), on), old.w);
}

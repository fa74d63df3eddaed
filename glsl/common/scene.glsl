// Scene records (std430) shared by the splat, gather and shade passes, mirrored in Rust by
// `src/render/records.rs` (tests/render_records.rs pins sizes and offsets against this file).
#ifndef SCENE_GLSL
#define SCENE_GLSL
#include "dipole.glsl"

const uint MATERIAL_OPAQUE = 0u;
const uint MATERIAL_TRANSLUCENT = 1u;

struct ObjectRecord {
    vec4 albedo_roughness;  // rgb: albedo: opaque, Lambert's; translucent, R_d,total per channel
                            // (dipole_r_d_total, taken once in f64); w: GGX roughness (both kinds)
    float eta;              // relative index of refraction
    float norm;             // BSSRDF normalization 1 / (pi T(eta)), T(eta) = 1 - 2 FM1(eta)
                            // (optics::Dipole::s_d); 0 for opaque
    uint kind;              // MATERIAL_*
    uint local_channels;    // channels computed locally, bit c: channel c (render::plan)
    DipoleChannel dipole[3]; // per channel: alpha', sigma_tr, z_r, z_v in scene units
    uvec4 ranges;           // x: first vertex, y: vertex count, z: first sample, w: sample count
    vec4 near_blend;        // rgb: per channel, 1 / k^2 for the near blend's radius k sqrt(dA)
                            // (kernel::near_blend_radii); w: 0
};

// 1 in each channel whose exitance is gathered, 0 in each the planner computes locally
// (M = R_d,total E_t at the receiver itself; GpuScene::set_local_channels), from the mask of
// local channels (bit c: channel c).
vec3 gathered_channels(uint local) {
    return vec3((local & 1u) == 0u ? 1.0 : 0.0, (local & 2u) == 0u ? 1.0 : 0.0, (local & 4u) == 0u ? 1.0 : 0.0);
}

// The same for object `o`'s record.
vec3 object_gathered_channels(ObjectRecord o) {
    return gathered_channels(o.local_channels);
}

struct SampleRecord {
    vec4 position_area;     // xyz: world position; w: area weight (scene units^2)
    vec3 normal;            // unit shading normal
    uint face_normal;       // its triangle's unit normal, octahedral (records::pack_octahedral)
};

// records::pack_octahedral's inverse: the unit vector of two snorm16 octahedral coordinates.
vec3 unpack_octahedral(uint bits) {
    vec2 e = unpackSnorm2x16(bits);
    vec3 v = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (v.z < 0.0) v.xy = (1.0 - abs(e.yx)) * vec2(e.x >= 0.0 ? 1.0 : -1.0, e.y >= 0.0 ? 1.0 : -1.0);
    return normalize(v);
}

// records::pack_octahedral in GLSL: a unit vector as two snorm16 octahedral coordinates.
uint pack_octahedral(vec3 n) {
    n /= max(abs(n.x) + abs(n.y) + abs(n.z), 1e-30);
    vec2 e = n.z >= 0.0 ? n.xy : (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return packSnorm2x16(e);
}

// One sample's splat output (splat.comp writes it, the gathers read it).
struct SplatRecord {
    vec4 irradiance_area;   // rgb: transmitted irradiance E_i; w: area weight
    vec4 near_energy;       // rgb: near-field energy per channel (dipole_near_energy); w: the key
                            // lights' transmitted flux (the sum over channels)
    vec4 beam;              // xyz: direction inside after refraction, the key lights' weighted
                            // by transmitted flux (unit; -n where none reaches); w: the length
                            // of that weighted sum (0 where none reaches)
};

// One node of an object's sample hierarchy (sampling::SampleTree, packed by TreeNodeRecord):
// static, built on the CPU when the samples are placed.
struct TreeNodeRecord {
    vec4 center_radius;     // xyz: centre of the bounding sphere of its samples; w: radius
    vec4 area_reach;        // x: total area; y: largest near-blend radius; z: mean area; w: 0
    uvec4 range_skip;       // x: first order entry; y: sample count; z: node after the subtree; w: leaf
};

// Per node, after each splat (gather_tree.comp stage 0).
struct NodePowerRecord {
    vec4 power;             // rgb: sum E_i A_i per channel; w: the members' mean area (TreeNodeRecord)
    vec4 mean_weight;       // xyz: power-weighted centroid; w: total weight
    vec4 cov_diag;          // xyz: power-weighted covariance of the members about it: xx, yy, zz
    vec4 cov_off;           // xyz: xy, xz, yz
};

// Per node, after each splat, for the between-points single scattering (beam_gather.comp
// stage 0; BeamNodeRecord in src/render/records.rs).
struct BeamNodeRecord {
    vec4 power;             // rgb: sum A_i E_i per channel; w: sum A_i
    vec4 position;          // xyz: the members' area-weighted centroid; w: sum P_i, P_i = A_i (E_r + E_g + E_b)
    vec4 normal;            // xyz: sum A_i n_i; w: 0
    vec4 beam;              // xyz: sum P_i w_i over the members' beams w_i; w: 0
};

// Per vertex, what the between-points single scattering's stage 1 knows of it before any frame
// (BeamReceiverRecord in src/render/records.rs; render::beam_gather::receiver_walks).
struct BeamReceiverRecord {
    vec3 norm;              // the density correction's denominator per channel
    uint first_item;        // its walk's first item in beam_items; the next vertex's ends it
};

// Per sample in its hierarchy's leaf order, after each splat, what the between-points single
// scattering reads of it (beam_gather.comp stage 0 writes it; BeamSourceRecord in
// src/render/records.rs).
struct BeamSourceRecord {
    vec4 position_mu;       // xyz: position; w: mu, the cosine of its beam with the inward normal
    vec4 power_area;        // rgb: A E per channel; w: A
    vec4 normal_along;      // xyz: unit normal; w: the beam's direction along the tangent plane,
                            // unit, octahedral (pack_octahedral) as float bits; any tangent at mu = 1
};

// One group of the hierarchical gather's receivers (ReceiverGroupRecord; sampling::ReceiverGroups).
struct ReceiverGroupRecord {
    vec4 center_radius;     // xyz: centre of a sphere holding its receivers; w: radius
    uvec4 items;            // hierarchical gather: x: first entry in the group items; y: its node
                            // items, which come first; z: its sample items, which follow; w: 0
    uvec4 blend;            // sparse gather: x: first entry in the blend items; y: count; z, w: 0
};

// An item of a group's list is a sample index, or NODE_ITEM | a node index (sampling::NODE_ITEM).
const uint NODE_ITEM = 0x80000000u;

// One mesh vertex as compute passes read it (the raster passes read the same buffer as vertex
// attributes): tightly packed, 24 bytes.
struct VertexRecord {
    float position[3];
    float normal[3];
};

vec3 vertex_position(VertexRecord v) {
    return vec3(v.position[0], v.position[1], v.position[2]);
}

vec3 vertex_normal(VertexRecord v) {
    return vec3(v.normal[0], v.normal[1], v.normal[2]);
}

#endif

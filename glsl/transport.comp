#version 450
// The transport kernel (src/optics/transport.rs, its f64 twin): the dipole's exitance at the
// vertices of an object with material.model = "transport" (those of its level of detail this
// frame), scaled per patch of its surface to the radiative transfer through its own mesh, the
// entry direction and point carried in the kernel's basis (1, mu - mu_bar, t . u_JI,
// (x - x_J) . u_JI):
//     F_I = max(0, sum_J (W0_IJ Phi_J exp(g_IJ X_J . u_JI / Phi_J) + Wmu_IJ Phimu_J
//           + Wt_IJ T_J . u_JI)) / A_I,   g_IJ = Wx_IJ / W0_IJ (optics::transport::offset_factor)
//     Phi_J = sum_(samples s in J) A_s E_t(s), Phimu_J, T_J and X_J alike weighted by the
//     sample's mu_s - mu_bar, t_s (SampleFlux::from_splat) and x_s - x_J (x_J the entries'
//     mean, Patches::entry_centres), u_JI the unit direction in J's tangent plane towards I's
//     centre (Patches::toward); Wmu and Wt are 0 beyond each channel's reach
//     (optics::transport::entry_reach), so each patch lists the J within it
//     (TransportKernel::near)
//     D_I = sum_(level's vertices v in I) a_v M_d(v) / sum a_v   (a_v: the level's dual cells)
//     M(v) = M_d(v) sum_I w_vI (F_I / D_I) / sum_I w_vI   (its eight nearest patches, D_I > 0)
// Each level of detail has its own patch records (its vertices, its D), sharing the object's W.
// Three stages (push `stage.x`), each one dispatch per object, a barrier between them:
//   0: one invocation per patch: Phi, Phimu, T, X and D, summed over its items;
//   1: one invocation per patch: F, its rows of W against every patch's fluxes (kept where
//      it was made under this frame's splat generation);
//   2: one invocation per vertex: the scale, in the channels push.stage.w names (the others
//      take single scattering between points, which the pass before wrote), where some
//      neighbour's D is positive and the scaled value finite (else the dipole's value stays).
// Gathered visible-first (glsl/receiver_view.comp), a frame gathers (state GATHER) and scales
// (FINISH) only some vertices, and D needs every vertex of a patch: so stage 0 keeps each
// vertex's dipole value, as the gather left it, in `dipole` (w: the generation, push.frame.x),
// reads D from there, and stage 2 scales the FINISH vertices from there. push.frame.y = 1:
// every vertex was gathered and is scaled (a scope of every receiver).
// Bindings: 0 = splat (SplatRecord[], read), 1 = exitance (vec4 per vertex, read by stage 0,
// written by stage 2), 2 = patches (TransportPatchRecord[]), 3 = items (uvec2: index, area
// bits), 4 = the kernels' rows (W0: a vec4 per pair, rgb; Wx alike after them; then per patch
// its near list, two vec4 per J: Wmu rgb with J in w, exact as a float; Wt rgb), 5 = sums
// (SUMS vec4 per patch: Phi, D, F (w: its generation's bits), Phimu, T_r, T_g, T_b, X_r, X_g,
// X_b; written by stages 0 and 1), 6 = neighbours (four uvec4 per vertex: (patch relative to
// the level's first record, weight bits) pairs), 7 = level vertices (uint[], object-relative),
// 8 = samples (SampleRecord[]: the normals), 9 = receiver
// state (uvec2 per vertex: generation, GATHER | FINISH), 10 = transport dipole (vec4 per vertex:
// the dipole's exitance, w the generation's bits). Push: TransportPush.
#include "scene.glsl"

layout(local_size_x = 64) in;

struct TransportPatchRecord {
    uvec4 items;    // x: first item; y: vertices; z: samples (after them); w: its rows' first entry
    vec4 area;      // x: area; y: mu_bar, the mean cosine of the kernel's entries
    vec4 centre;    // xyz: centre
    vec4 normal;    // xyz: unit mean normal (0 where the patch's normals cancel)
    uvec4 near;     // x: its near list's first entry in the rows; y: its length
    vec4 entry;     // xyz: the entries' mean x_J
};

const uint SUMS = 10u;
const float OFFSET_EXPONENT_LIMIT = 2.0;  // optics::transport::OFFSET_EXPONENT_LIMIT

layout(std430, set = 0, binding = 0) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 1) buffer Exitance { vec4 exitance[]; };
layout(std430, set = 0, binding = 2) readonly buffer TransportPatches { TransportPatchRecord patches[]; };
layout(std430, set = 0, binding = 3) readonly buffer TransportItems { uvec2 items[]; };
layout(std430, set = 0, binding = 4) readonly buffer TransportMatrix { vec4 matrix[]; };
layout(std430, set = 0, binding = 5) buffer TransportSums { vec4 sums[]; };
layout(std430, set = 0, binding = 6) readonly buffer TransportNeighbours { uvec4 neighbours[]; };
layout(std430, set = 0, binding = 7) readonly buffer LevelVertices { uint level_vertices[]; };
layout(std430, set = 0, binding = 8) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 9) readonly buffer ReceiverState { uvec2 receiver_state[]; };
layout(std430, set = 0, binding = 10) buffer TransportDipole { vec4 dipole[]; };

#define GATHER 1u  // glsl/receiver_view.comp: gathered this frame
#define FINISH 2u  // glsl/receiver_view.comp: scaled this frame

struct TransportPush {
    uvec4 stage;    // x: the stage; y: the object's first patch; z: its patches; w: the
                    // channels it scales (bit c)
    uvec4 vertices; // x: its first vertex; y: the level's vertices; z: the object's first
                    // neighbour entry; w: the level's first entry in level_vertices
    uvec4 frame;    // x: the splat generation; y: 1 where every vertex was gathered
};
layout(push_constant) uniform Push { TransportPush push; };

// Sample item `it`'s weighted irradiance into the lane's sums: A_s E_t, and that times
// mu_s - mu_bar, t_s (SampleFlux::from_splat) and x_s - x_J (`entry`).
void add_sample(uvec2 it, vec4 at, inout vec3 phi, inout vec3 phi_mu, inout vec3 t[3], inout vec3 x[3]) {
    SplatRecord r = splat[it.x];
    vec3 e = r.irradiance_area.rgb;
    SampleRecord s = samples[it.x];
    vec3 n = s.normal, offset = s.position_area.xyz - at.xyz;
    float mu_bar = at.w;
    float w = e.r + e.g + e.b;
    float mu = mu_bar;
    vec3 tilt = vec3(0.0);
    if (w > 0.0) {
        vec3 d_key = r.beam.xyz * r.beam.w;
        float along = dot(d_key, n);
        mu = (-along + (w - r.near_energy.w) * mu_bar) / w;
        tilt = (d_key - n * along) / w;
    }
    vec3 f = uintBitsToFloat(it.y) * e;
    phi += f;
    phi_mu += f * (mu - mu_bar);
    for (int c = 0; c < 3; ++c) {
        t[c] += tilt * f[c];
        x[c] += offset * f[c];
    }
}

// Vertex v's dipole exitance this generation; kept in `dipole` where this frame gathered it
// (each vertex lies in one patch of the level: one writer).
vec3 dipole_value(uint v) {
    if (push.frame.y == 0u && (receiver_state[v].y & GATHER) == 0u) return dipole[v].rgb;
    vec3 m = exitance[v].rgb;
    dipole[v] = vec4(m, uintBitsToFloat(push.frame.x));
    return m;
}

// Stage 0: patch `p`'s Phi, Phimu, T, X and D, one invocation walking its items (a patch has a
// few hundred; a workgroup per patch summing six arrays through shared memory and six barriers
// was no faster on lavapipe).
void patch_sums(uint p) {
    TransportPatchRecord r = patches[p];
    vec3 phi = vec3(0.0), phi_mu = vec3(0.0);
    vec3 t[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    vec3 x[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    vec4 d = vec4(0.0);
    for (uint k = 0u; k < r.items.y; ++k) {
        uvec2 it = items[r.items.x + k];
        float a = uintBitsToFloat(it.y);
        d += vec4(a * dipole_value(it.x), a);
    }
    for (uint k = 0u; k < r.items.z; ++k) {
        add_sample(items[r.items.x + r.items.y + k], vec4(r.entry.xyz, r.area.y), phi, phi_mu, t, x);
    }
    sums[SUMS * p] = vec4(phi, 0.0);
    // The dipole's mean over the level's vertices in the patch (0 where it has none).
    sums[SUMS * p + 1u] = vec4(d.w > 0.0 ? d.rgb / d.w : vec3(0.0), 0.0);
    sums[SUMS * p + 3u] = vec4(phi_mu, 0.0);
    for (uint c = 0u; c < 3u; ++c) {
        sums[SUMS * p + 4u + c] = vec4(t[c], 0.0);
        sums[SUMS * p + 7u + c] = vec4(x[c], 0.0);
    }
}

// The unit direction in patch `j`'s tangent plane towards `to` (Patches::toward), its record read
// only for its centre and normal (llvmpipe loads a whole record passed by value).
vec3 toward(uint j, vec3 to) {
    vec3 n = patches[j].normal.xyz, d = to - patches[j].centre.xyz;
    vec3 u = d - n * dot(d, n);
    float l2 = dot(u, u);
    return l2 > 0.0 ? u * inversesqrt(l2) : vec3(0.0);
}

// optics::transport::offset_factor per channel: exp(Wx X.u / (W0 Phi)), limited; 1 where
// W0 Phi is not positive.
vec3 offset_factor(vec3 w0, vec3 wx, vec3 x_u, vec3 phi) {
    vec3 s = vec3(1.0);
    for (int c = 0; c < 3; ++c) {
        float den = w0[c] * phi[c];
        if (den > 0.0) s[c] = exp(clamp(wx[c] * x_u[c] / den, -OFFSET_EXPONENT_LIMIT, OFFSET_EXPONENT_LIMIT));
    }
    return s;
}

// Stage 1: patch `p`'s F from its rows of the kernel, w the splat generation it was made under.
// F depends on the splat alone (its Phi, Phimu, T and X): a visible-first frame that keeps the
// generation (a camera frame's newly seen receivers, a sweep's chunk) keeps F, and only stage 0's
// D and stage 2 run. Every-receiver frames (generation 0, which no visible-first frame has)
// always make it.
void patch_transport(uint p) {
    if (push.frame.y == 0u && floatBitsToUint(sums[SUMS * p + 2u].w) == push.frame.x) return;
    TransportPatchRecord r = patches[p];
    uint first = push.stage.y, k = push.stage.z;
    vec3 f = vec3(0.0);
    for (uint j = 0u; j < k; ++j) {
        uint q = SUMS * (first + j);
        vec3 u = toward(first + j, r.centre.xyz);
        vec3 xu = vec3(dot(sums[q + 7u].xyz, u), dot(sums[q + 8u].xyz, u), dot(sums[q + 9u].xyz, u));
        vec3 w0 = matrix[r.items.w + j].rgb, phi = sums[q].rgb;
        f += w0 * phi * offset_factor(w0, matrix[r.items.w + k * k + j].rgb, xu, phi);
    }
    for (uint k = 0u; k < r.near.y; ++k) {
        vec4 mu = matrix[r.near.x + 2u * k], tilt = matrix[r.near.x + 2u * k + 1u];
        uint j = uint(mu.w), q = SUMS * (first + j);
        vec3 u = toward(first + j, r.centre.xyz);
        vec3 tu = vec3(dot(sums[q + 4u].xyz, u), dot(sums[q + 5u].xyz, u), dot(sums[q + 6u].xyz, u));
        f += mu.rgb * sums[q + 3u].rgb + tilt.rgb * tu;
    }
    // Linear in the entry: never below zero (TransportKernel::transport_exitance).
    sums[SUMS * p + 2u] = vec4(max(f / r.area.x, vec3(0.0)), uintBitsToFloat(push.frame.x));
}

// One neighbour (patch relative to the level's first record, weight bits) into the blend of
// the ratios F / D, in the channels where its D is positive.
void add_ratio(uvec2 pair, uint first, inout vec3 ratio, inout vec3 weight) {
    float w = uintBitsToFloat(pair.y);
    uint q = SUMS * (first + pair.x);
    vec3 f = sums[q + 2u].rgb, d = sums[q + 1u].rgb;
    for (int c = 0; c < 3; ++c) {
        if (d[c] > 0.0) {
            ratio[c] += w * (f[c] / d[c]);
            weight[c] += w;
        }
    }
}

// Stage 2: vertex `i` of the level scaled by its neighbours' blend.
void scale_vertex(uint i) {
    uint rel = level_vertices[push.vertices.w + i];
    uint v = push.vertices.x + rel;
    // Gathered visible-first, the rest wait their turn (and hold the dipole's value or an older
    // generation's).
    if (push.frame.y == 0u && (receiver_state[v].y & FINISH) == 0u) return;
    uint first = push.stage.y;
    vec3 ratio = vec3(0.0), weight = vec3(0.0);
    for (uint k = 0u; k < 4u; ++k) {
        uvec4 pairs = neighbours[push.vertices.z + 4u * rel + k];
        add_ratio(pairs.xy, first, ratio, weight);
        add_ratio(pairs.zw, first, ratio, weight);
    }
    vec4 m = vec4(dipole[v].rgb, exitance[v].w);
    for (int c = 0; c < 3; ++c) {
        // An overflowed dipole exitance or ratio would be Inf or NaN: keep the dipole's.
        float s = m[c] * (ratio[c] / weight[c]);
        bool scaled = (push.stage.w & (1u << uint(c))) != 0u;
        if (scaled && weight[c] > 0.0 && !isinf(s) && !isnan(s)) m[c] = s;
    }
    exitance[v] = m;
}

void main() {
    uint stage = push.stage.x;
    if (stage == 0u) {
        if (gl_GlobalInvocationID.x < push.stage.z) patch_sums(push.stage.y + gl_GlobalInvocationID.x);
    } else if (stage == 1u) {
        if (gl_GlobalInvocationID.x < push.stage.z) patch_transport(push.stage.y + gl_GlobalInvocationID.x);
    } else if (gl_GlobalInvocationID.x < push.vertices.y) {
        scale_vertex(gl_GlobalInvocationID.x);
    }
}

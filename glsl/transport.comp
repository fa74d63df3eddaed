#version 450
// The transport kernel (src/optics/transport.rs, its f64 twin): the dipole's exitance at the
// vertices of an object with material.model = "transport" (those of its level of detail this
// frame), scaled per patch of its surface to the radiative transfer through its own mesh:
//     F_I = sum_J W_IJ Phi_J / A_I,   Phi_J = sum_(samples s in J) A_s E_t(s)
//     D_I = sum_(level's vertices v in I) a_v M_d(v) / sum a_v   (a_v: the level's dual cells)
//     M(v) = M_d(v) sum_I w_vI F_I / sum_I w_vI D_I   (its eight nearest patches)
// Each level of detail has its own patch records (its vertices, its D), sharing the object's W.
// Three stages (push `stage.x`), each one dispatch per object, a barrier between them:
//   0: one workgroup per patch: Phi and D, summed over its items in shared memory;
//   1: one invocation per patch: F, its row of W against every patch's Phi;
//   2: one invocation per vertex: the scale, in the channels push.stage.w names (the others
//      take single scattering between points, which the pass before wrote), where the blended
//      D is positive and the ratio finite (else the dipole's value stays).
// Bindings: 0 = splat (SplatRecord[], read), 1 = exitance (vec4 per vertex, read by stage 0,
// written by stage 2), 2 = patches (TransportPatchRecord[]), 3 = items (uvec2: index, area
// bits), 4 = the kernels' W (vec4 per pair, rgb), 5 = sums (three vec4 per patch: Phi, D, F;
// written by stages 0 and 1), 6 = neighbours (four uvec4 per vertex: (patch relative to the
// level's first record, weight bits) pairs), 7 = level vertices (uint[], object-relative).
// Push: TransportPush.
#include "scene.glsl"

layout(local_size_x = 64) in;

struct TransportPatchRecord {
    uvec4 items;    // x: first item; y: vertices; z: samples (after them); w: W's row
    vec4 area;      // x: area
};

layout(std430, set = 0, binding = 0) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 1) buffer Exitance { vec4 exitance[]; };
layout(std430, set = 0, binding = 2) readonly buffer TransportPatches { TransportPatchRecord patches[]; };
layout(std430, set = 0, binding = 3) readonly buffer TransportItems { uvec2 items[]; };
layout(std430, set = 0, binding = 4) readonly buffer TransportMatrix { vec4 matrix[]; };
layout(std430, set = 0, binding = 5) buffer TransportSums { vec4 sums[]; };
layout(std430, set = 0, binding = 6) readonly buffer TransportNeighbours { uvec4 neighbours[]; };
layout(std430, set = 0, binding = 7) readonly buffer LevelVertices { uint level_vertices[]; };

struct TransportPush {
    uvec4 stage;    // x: the stage; y: the object's first patch; z: its patches; w: the
                    // channels it scales (bit c)
    uvec4 vertices; // x: its first vertex; y: the level's vertices; z: the object's first
                    // neighbour entry; w: the level's first entry in level_vertices
};
layout(push_constant) uniform Push { TransportPush push; };

shared vec3 part_phi[64];
shared vec4 part_d[64];

// Stage 0: patch `p`'s Phi and D, its items split over the workgroup.
void patch_sums(uint p) {
    TransportPatchRecord r = patches[p];
    uint lane = gl_LocalInvocationID.x;
    vec3 phi = vec3(0.0);
    vec4 d = vec4(0.0);
    for (uint k = lane; k < r.items.y; k += 64u) {
        uvec2 it = items[r.items.x + k];
        float a = uintBitsToFloat(it.y);
        d += vec4(a * exitance[it.x].rgb, a);
    }
    for (uint k = lane; k < r.items.z; k += 64u) {
        uvec2 it = items[r.items.x + r.items.y + k];
        phi += uintBitsToFloat(it.y) * splat[it.x].irradiance_area.rgb;
    }
    part_phi[lane] = phi;
    part_d[lane] = d;
    barrier();
    for (uint half_ = 32u; half_ > 0u; half_ >>= 1) {
        if (lane < half_) {
            part_phi[lane] += part_phi[lane + half_];
            part_d[lane] += part_d[lane + half_];
        }
        barrier();
    }
    if (lane == 0u) {
        sums[3u * p] = vec4(part_phi[0], 0.0);
        // The dipole's mean over the level's vertices in the patch (0 where it has none).
        vec4 s = part_d[0];
        sums[3u * p + 1u] = vec4(s.w > 0.0 ? s.rgb / s.w : vec3(0.0), 0.0);
    }
}

// Stage 1: patch `p`'s F from its row of W.
void patch_transport(uint p) {
    TransportPatchRecord r = patches[p];
    uint first = push.stage.y;
    vec3 f = vec3(0.0);
    for (uint j = 0u; j < push.stage.z; ++j) {
        f += matrix[r.items.w + j].rgb * sums[3u * (first + j)].rgb;
    }
    sums[3u * p + 2u] = vec4(f / r.area.x, 0.0);
}

// Stage 2: vertex `i` of the level scaled by its neighbours' blend.
void scale_vertex(uint i) {
    uint rel = level_vertices[push.vertices.w + i];
    uint v = push.vertices.x + rel;
    uint first = push.stage.y;
    vec3 f = vec3(0.0), d = vec3(0.0);
    for (uint k = 0u; k < 4u; ++k) {
        uvec4 pair = neighbours[push.vertices.z + 4u * rel + k];
        float w0 = uintBitsToFloat(pair.y), w1 = uintBitsToFloat(pair.w);
        uint p0 = 3u * (first + pair.x), p1 = 3u * (first + pair.z);
        f += w0 * sums[p0 + 2u].rgb + w1 * sums[p1 + 2u].rgb;
        d += w0 * sums[p0 + 1u].rgb + w1 * sums[p1 + 1u].rgb;
    }
    vec4 m = exitance[v];
    for (int c = 0; c < 3; ++c) {
        float ratio = f[c] / d[c];
        bool scaled = (push.stage.w & (1u << uint(c))) != 0u;
        if (scaled && d[c] > 0.0 && !isinf(ratio) && !isnan(ratio)) m[c] *= ratio;
    }
    exitance[v] = m;
}

void main() {
    uint stage = push.stage.x;
    if (stage == 0u) {
        patch_sums(push.stage.y + gl_WorkGroupID.x);
    } else if (stage == 1u) {
        if (gl_GlobalInvocationID.x < push.stage.z) patch_transport(push.stage.y + gl_GlobalInvocationID.x);
    } else if (gl_GlobalInvocationID.x < push.vertices.y) {
        scale_vertex(gl_GlobalInvocationID.x);
    }
}

#version 450
// Which receivers of one object the hierarchical gather recomputes this frame (src/render/plan/
// receivers.rs): among those whose exitance was not gathered under this generation of the
// object's splat, the ones an eye may see and this frame's chunk of the sweep over the rest.
// A receiver may be seen when it lies in the view frustum widened by its level's longest edge
// (a vertex of a triangle that meets the frustum lies no farther outside it) and, where the
// shading pass culls hidden faces, when its facing cone (mesh::facing::vertex_cones) holds a
// normal towards the eye. mesh::facing::faces_eye and plan::View::sees are the f32 twins.
// A receiver it picks is marked with the generation at once: stage 1 of glsl/gather_tree.comp
// gathers exactly the picked ones (bit GATHER of the state's y) in the same frame.
//
// An object whose exitance a transport kernel scales (glsl/transport.comp) needs more: a picked
// vertex's value blends its eight patches' ratios F_I / D_I, and D_I is the mean dipole exitance
// over all of patch I's vertices. So for such an object (flag KERNEL) the state's x is the
// generation a vertex was *scaled* under, a picked vertex is marked FINISH, and two more stages
// (push `stage`) follow, a barrier before each:
//   1 (per receiver): each FINISH vertex stamps its patches (TransportNeighbours) as needed;
//   2 (per patch of the level): a needed patch marks GATHER on its vertices whose dipole value
//     (glsl/transport.comp keeps it in TransportDipole, w = the generation it was gathered
//     under) is not of this generation.
// A patch's vertices are gathered once per generation; the ones no eye sees keep the dipole's
// value until their own turn scales them.
//
// Bindings: 0 = vertices (VertexRecord[]), 1 = receiver order (uint[]), 2 = receiver cones
// (vec4 per vertex), 3 = receiver state (uvec2 per vertex: generation, GATHER | FINISH),
// 4 = transport neighbours (four uvec4 per kernel vertex), 5 = transport patches
// (TransportPatchRecord[]), 6 = transport items (uvec2), 7 = transport needed (uint per patch
// record: the generation that last needed it), 8 = transport dipole (vec4 per vertex). Push:
// ReceiverViewPush.
#include "scene.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer ReceiverOrder { uint receiver_order[]; };
layout(std430, set = 0, binding = 2) readonly buffer ReceiverCones { vec4 receiver_cones[]; };
layout(std430, set = 0, binding = 3) buffer ReceiverState { uvec2 receiver_state[]; };
layout(std430, set = 0, binding = 4) readonly buffer TransportNeighbours { uvec4 neighbours[]; };
layout(std430, set = 0, binding = 5) readonly buffer TransportPatches { uvec4 patches[]; };
layout(std430, set = 0, binding = 6) readonly buffer TransportItems { uvec2 items[]; };
layout(std430, set = 0, binding = 7) buffer TransportNeeded { uint needed[]; };
layout(std430, set = 0, binding = 8) readonly buffer TransportDipole { vec4 dipole[]; };

#define VIEW_TEST 1u   // pick the receivers an eye may see
#define FACING_TEST 2u // the shading pass culls hidden faces: test the facing cone too
#define KERNEL 4u      // a transport kernel scales the object's exitance
#define ALWAYS 2.0     // mesh::facing::ALWAYS
#define GATHER 1u      // state.y: stage 1 of the gather computes its dipole exitance
#define FINISH 2u      // state.y: glsl/transport.comp scales it this frame
#define PATCH_UVEC4S 6u // TransportPatchRecord's size; its first uvec4 is `items`

struct ReceiverViewPush {
    mat4 view_proj;       // world -> clip (Vulkan depth 0..1)
    vec4 eye;             // [e, 1] for a perspective eye, [towards the eye, 0] for an orthographic one
    uint first_receiver;  // the level's first entry in receiver_order
    uint receiver_count;  // its receivers
    uint generation;      // the object's splat generation
    uint flags;           // VIEW_TEST | FACING_TEST
    uint sweep[2];        // this frame's chunk of the sweep, in receiver order: first, count
    float reach;          // the level's longest edge
    uint stage;           // 0: pick; with KERNEL, 1: stamp the patches; 2: mark their vertices
    uvec4 kernel;         // x: the level's first patch record; y: its patches; z: the object's
                          // first neighbour entry; w: its first vertex
};
layout(push_constant) uniform ReceiverViewPushBlock { ReceiverViewPush push; };

// Inside the six clip planes (Gribb and Hartmann's extraction from the matrix's rows), each
// moved out by `reach`; a degenerate plane (an infinite far plane) passes.
bool in_frustum(vec3 x, float reach) {
    mat4 m = push.view_proj;
    vec4 r0 = vec4(m[0][0], m[1][0], m[2][0], m[3][0]);
    vec4 r1 = vec4(m[0][1], m[1][1], m[2][1], m[3][1]);
    vec4 r2 = vec4(m[0][2], m[1][2], m[2][2], m[3][2]);
    vec4 r3 = vec4(m[0][3], m[1][3], m[2][3], m[3][3]);
    vec4 planes[6] = vec4[6](r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2);
    for (int i = 0; i < 6; ++i) {
        float len = length(planes[i].xyz);
        if (len != 0.0 && dot(planes[i], vec4(x, 1.0)) < -reach * len) return false;
    }
    return true;
}

// mesh::facing::faces_eye.
bool faces_eye(vec4 cone, vec3 x) {
    if (cone.w >= ALWAYS) return true;
    vec3 d = push.eye.w != 0.0 ? push.eye.xyz - x : push.eye.xyz;
    return dot(cone.xyz, d) > -cone.w * length(d);
}

// Whether vertex v's dipole value is of this generation.
bool dipole_current(uint v) {
    return floatBitsToUint(dipole[v].w) == push.generation;
}

// Stage 1: the receiver's patches, where it is scaled this frame, are needed.
void stamp_patches(uint v) {
    if ((receiver_state[v].y & FINISH) == 0u) return;
    uint base = push.kernel.z + 4u * (v - push.kernel.w);
    for (uint k = 0u; k < 4u; ++k) {
        uvec4 pair = neighbours[base + k];
        // A zero weight pads a short list: its patch is not blended.
        if (pair.y != 0u) needed[push.kernel.x + pair.x] = push.generation;
        if (pair.w != 0u) needed[push.kernel.x + pair.z] = push.generation;
    }
}

// Stage 2: patch p's vertices whose dipole value is older are gathered, where p is needed.
void mark_patch(uint p) {
    if (needed[p] != push.generation) return;
    uvec4 r = patches[PATCH_UVEC4S * p];
    for (uint k = 0u; k < r.y; ++k) {
        uint v = items[r.x + k].x;
        if (!dipole_current(v)) receiver_state[v].y |= GATHER;
    }
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (push.stage == 2u) {
        if (k < push.kernel.y) mark_patch(push.kernel.x + k);
        return;
    }
    if (k >= push.receiver_count) return;
    uint v = receiver_order[push.first_receiver + k];
    if (push.stage == 1u) {
        stamp_patches(v);
        return;
    }
    uvec2 state = receiver_state[v];
    bool swept = k - push.sweep[0] < push.sweep[1];
    bool seen = false;
    if ((push.flags & VIEW_TEST) != 0u) {
        vec3 x = vertex_position(vertices[v]);
        seen = in_frustum(x, push.reach) && ((push.flags & FACING_TEST) == 0u || faces_eye(receiver_cones[v], x));
    }
    bool picked = state.x != push.generation && (swept || seen);
    uint flags = GATHER;
    if ((push.flags & KERNEL) != 0u) flags = FINISH | (dipole_current(v) ? 0u : GATHER);
    receiver_state[v] = picked ? uvec2(push.generation, flags) : uvec2(state.x, 0u);
}

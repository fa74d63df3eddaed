#version 450
// Which receivers of one object the hierarchical gather recomputes this frame (src/render/plan/
// receivers.rs): among those whose exitance was not gathered under this generation of the
// object's splat, the ones an eye may see and this frame's chunk of the sweep over the rest.
// A receiver may be seen when it lies in the view frustum widened by its level's longest edge
// (a vertex of a triangle that meets the frustum lies no farther outside it) and, where the
// shading pass culls hidden faces, when its facing cone (mesh::facing::vertex_cones) holds a
// normal towards the eye. mesh::facing::faces_eye and plan::View::sees are the f32 twins.
// A receiver it picks is marked with the generation at once: stage 1 of glsl/gather_tree.comp
// gathers exactly the picked ones in the same frame.
//
// Bindings: 0 = vertices (VertexRecord[]), 1 = receiver order (uint[]), 2 = receiver cones
// (vec4 per vertex), 3 = receiver state (uvec2 per vertex: generation, picked). Push:
// ReceiverViewPush.
#include "scene.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer ReceiverOrder { uint receiver_order[]; };
layout(std430, set = 0, binding = 2) readonly buffer ReceiverCones { vec4 receiver_cones[]; };
layout(std430, set = 0, binding = 3) buffer ReceiverState { uvec2 receiver_state[]; };

#define VIEW_TEST 1u   // pick the receivers an eye may see
#define FACING_TEST 2u // the shading pass culls hidden faces: test the facing cone too
#define ALWAYS 2.0     // mesh::facing::ALWAYS

struct ReceiverViewPush {
    mat4 view_proj;       // world -> clip (Vulkan depth 0..1)
    vec4 eye;             // [e, 1] for a perspective eye, [towards the eye, 0] for an orthographic one
    uint first_receiver;  // the level's first entry in receiver_order
    uint receiver_count;  // its receivers
    uint generation;      // the object's splat generation
    uint flags;           // VIEW_TEST | FACING_TEST
    uint sweep[2];        // this frame's chunk of the sweep, in receiver order: first, count
    float reach;          // the level's longest edge
    uint pad;
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

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= push.receiver_count) return;
    uint v = receiver_order[push.first_receiver + k];
    uvec2 state = receiver_state[v];
    bool swept = k - push.sweep[0] < push.sweep[1];
    bool seen = false;
    if ((push.flags & VIEW_TEST) != 0u) {
        vec3 x = vertex_position(vertices[v]);
        seen = in_frustum(x, push.reach) && ((push.flags & FACING_TEST) == 0u || faces_eye(receiver_cones[v], x));
    }
    bool picked = state.x != push.generation && (swept || seen);
    receiver_state[v] = picked ? uvec2(push.generation, 1u) : uvec2(state.x, 0u);
}

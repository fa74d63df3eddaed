#version 450
// Test pass (tests/graph.rs): a new reader of the gathers' exitance, which no producer names.
// Bindings: 0 = exitance (vec4 per vertex, read), 1 = probe (vec4 per vertex, written).
// Push: vertex count.
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Exitance { vec4 exitance[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Probe { vec4 probe[]; };
layout(push_constant) uniform Push { uint count; } push;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) return;
    probe[i] = exitance[i];
}

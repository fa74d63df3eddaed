#version 450
// Smoke pass: out[i] = 2 * in[i] + i. Proves upload, dispatch and readback.
// Bindings: 0 = input floats (read), 1 = output floats (write). Push: element count.
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Input { float values_in[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Output { float values_out[]; };
layout(push_constant) uniform Push { uint count; } push;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) return;
    values_out[i] = 2.0 * values_in[i] + float(i);
}

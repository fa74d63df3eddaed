#version 450
// Probe pass (src/render/probe.rs, a test's pass): a new pass that reads one scene buffer and
// writes another, local_exitance[v] = 2 exitance[v], to show what registering a pass takes.
// Bindings: 0 = exitance (vec4 per vertex, read), 1 = local exitance (vec4 per vertex, written).
// Push: the vertex count.
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Exitance { vec4 exitance[]; };
layout(std430, set = 0, binding = 1) writeonly buffer LocalExitance { vec4 local_exitance[]; };
layout(push_constant) uniform ProbePush { uint vertex_count; } push;

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= push.vertex_count) return;
    local_exitance[v] = 2.0 * exitance[v];
}

#version 450
// Test of the graphics path: one coloured triangle from a vertex buffer.
layout(location = 0) in vec2 position;
layout(location = 1) in vec3 color;
layout(location = 0) out vec3 v_color;
layout(push_constant) uniform Push { float depth; } push;

void main() {
    v_color = color;
    gl_Position = vec4(position, push.depth, 1.0);
}

#version 450
// Shadow maps: depth of every shadow-casting object seen from one light (one array layer per
// light). Depth only, no fragment shader. Vertex input: binding 0 = position (vec3) + normal.
// Push: the light's world -> clip matrix.
layout(location = 0) in vec3 position;
layout(push_constant) uniform Push { mat4 light_matrix; } push;

void main() {
    gl_Position = push.light_matrix * vec4(position, 1.0);
}

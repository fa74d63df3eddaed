#version 450
// examples/embed.rs: the host engine's own geometry, a flat quad of one colour, drawn before
// translucent's passes into the same colour and depth images.
layout(location = 0) in vec3 position;
struct GroundPush {
    mat4 view_proj;
    vec4 color;
};
layout(push_constant) uniform GroundPushBlock { GroundPush push; };

void main() {
    gl_Position = push.view_proj * vec4(position, 1.0);
}

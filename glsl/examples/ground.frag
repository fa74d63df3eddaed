#version 450
// examples/embed.rs: the host's quad, one linear colour.
layout(location = 0) out vec4 color;
struct GroundPush {
    mat4 view_proj;
    vec4 color;
};
layout(push_constant) uniform GroundPushBlock { GroundPush push; };

void main() {
    color = push.color;
}

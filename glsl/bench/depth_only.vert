#version 450
// The benchmark's shadow yardstick (benches/render/roofline.rs): the shadow casters depth-only
// into one layer, with no layer selection and no depth bias. Vertex input: binding 0 = position.
// Push: the light's world -> clip.
layout(location = 0) in vec3 position;
layout(push_constant) uniform DepthOnlyPushBlock { mat4 light_matrix; } push;

void main() {
    gl_Position = push.light_matrix * vec4(position, 1.0);
}

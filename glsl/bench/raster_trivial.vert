#version 450
// The benchmark's raster yardstick (benches/render/roofline.rs), not a renderer pass: the shading
// pass's geometry (same vertex buffer, levels and targets) with the least a vertex stage can do,
// one interpolant. Vertex input: binding 0 = position, normal. Push: the camera's world -> clip.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 0) out vec3 v_normal;
layout(push_constant) uniform TrivialPushBlock { mat4 view_proj; } push;

void main() {
    v_normal = normal;
    gl_Position = push.view_proj * vec4(position, 1.0);
}

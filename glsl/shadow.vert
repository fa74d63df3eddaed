#version 450
#extension GL_ARB_shader_viewport_layer_array : require
// Shadow maps: depth of every shadow-casting object seen from each shadow-casting light, all
// lights in one layered render of a D16 array image; gl_Layer picks the light's layer.
// Depth only, no fragment shader. Vertex input: binding 0 = position (vec3) + normal.
// Push: the light's world -> clip matrix and its layer.
layout(location = 0) in vec3 position;
struct ShadowPush {
    mat4 light_matrix;      // world -> the light's clip space
    uvec4 layer;            // x: the shadow-map layer (gl_Layer); yzw: unused
};
layout(push_constant) uniform ShadowPushBlock { ShadowPush push; };

void main() {
    gl_Position = push.light_matrix * vec4(position, 1.0);
    gl_Layer = int(push.layer.x);
}

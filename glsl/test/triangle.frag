#version 450
layout(location = 0) in vec3 v_color;
layout(location = 0) out vec4 out_color;
// Bindings: 0 = storage buffer with a tint multiplied into the colour (exercises descriptors).
layout(std430, set = 0, binding = 0) readonly buffer Tint { vec4 tint; };

void main() {
    out_color = vec4(v_color * tint.rgb, 1.0);
}

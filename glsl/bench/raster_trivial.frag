#version 450
// The raster yardstick's fragment stage: the interpolated normal as a colour, nothing else.
layout(location = 0) in vec3 v_normal;
layout(location = 0) out vec4 out_colour;
layout(push_constant) uniform TrivialPushBlock { mat4 view_proj; } push;

void main() {
    out_colour = vec4(v_normal * 0.5 + 0.5, 1.0);
}

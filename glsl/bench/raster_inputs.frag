#version 450
// The raster yardstick with the shading pass's own vertex stage (shade.vert) and every one of
// its interpolants read, nothing computed: what rasterising and interpolating those inputs cost.
layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec3 v_exitance;
layout(location = 3) in vec3 v_environment;
layout(location = 0) out vec4 out_colour;

void main() {
    out_colour = vec4(v_exitance + v_environment + 1e-6 * (v_position + v_normal), 1.0);
}

#version 450
// The G-buffer of a deferred shading yardstick: the shading pass's vertex stage (shade.vert) with
// its four interpolants written out as they arrive, for glsl/bench/shade_compute.comp to shade.
layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec3 v_exitance;
layout(location = 3) in vec3 v_environment;
layout(location = 0) out vec4 g_position;  // w: 1 where a surface covers the pixel
layout(location = 1) out vec4 g_normal;
layout(location = 2) out vec4 g_exitance;
layout(location = 3) out vec4 g_environment;

void main() {
    g_position = vec4(v_position, 1.0);
    g_normal = vec4(v_normal, 0.0);
    g_exitance = vec4(v_exitance, 0.0);
    g_environment = vec4(v_environment, 0.0);
}

#version 450
// Forward shading, vertex stage: world position, normal and (for translucent objects) the
// gathered radiant exitance, interpolated across triangles.
// Vertex input: binding 0 = position, normal; binding 1 = exitance; binding 2 = environment
// irradiance cached by vertex_light.comp (vec4 per vertex each).
// Push: ShadePush (glsl/common/shade_push.glsl).
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec4 exitance;
layout(location = 3) in vec4 environment_irradiance;
layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec3 v_exitance;
layout(location = 3) out vec3 v_environment;
#include "shade_push.glsl"

void main() {
    v_position = position;
    v_normal = normal;
    v_exitance = exitance.rgb;
    v_environment = environment_irradiance.rgb;
    gl_Position = push.view_proj * vec4(position, 1.0);
}

#version 450
// Forward shading, vertex stage: world position, normal and (for translucent objects) the
// gathered radiant exitance, interpolated across triangles.
// Vertex input: binding 0 = position, normal; binding 1 = exitance; binding 2 = environment
// irradiance cached by vertex_light.comp (vec4 per vertex each).
// Push: see shade.frag.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec4 exitance;
layout(location = 3) in vec4 environment_irradiance;
layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec3 v_exitance;
layout(location = 3) out vec3 v_environment;
layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 eye_object;        // xyz: camera position; w: object index
    uvec4 counts;           // x: light count; y: key (non-environment) lights, first in the buffer
} push;

void main() {
    v_position = position;
    v_normal = normal;
    v_exitance = exitance.rgb;
    v_environment = environment_irradiance.rgb;
    gl_Position = push.view_proj * vec4(position, 1.0);
}

#version 450
// Vertex light: irradiance from the environment's directional lights at every mesh vertex,
// sum_l E_l max(cos, 0) V_l with V from the shadow maps (4-tap PCF), cached per vertex. It is
// view-independent and changes only when the environment does, so a moving camera or a moving
// key light reuses it; the shading pass interpolates it for diffuse surfaces instead of looking
// up every environment shadow map at every pixel. One dispatch per object: for a translucent one
// the irradiance is the part transmitted through the surface, sum_l E_l cos F_t(cos, eta) V_l.
//
// Bindings: 0 = vertices (VertexRecord[]), 1 = lights (Light[]),
// 2 = shadow maps (sampler2DArrayShadow), 3 = output (vec4 per vertex: rgb irradiance).
// Push: VertexLightPush.
#include "dipole.glsl"
#include "lights.glsl"
#include "scene.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Lights { Light lights[]; };
layout(set = 0, binding = 2) uniform sampler2DArrayShadow shadow_maps;
layout(std430, set = 0, binding = 3) writeonly buffer EnvironmentIrradiance { vec4 irradiance_out[]; };
struct VertexLightPush {
    uint first_vertex;
    uint vertex_count;
    uint light_count;
    float eta;              // > 0: a translucent object's index of refraction; 0: opaque
};
layout(push_constant) uniform VertexLightPushBlock { VertexLightPush push; };

void main() {
    if (gl_GlobalInvocationID.x >= push.vertex_count) return;
    uint v = push.first_vertex + gl_GlobalInvocationID.x;
    vec3 p = vertex_position(vertices[v]);
    vec3 n = normalize(vertex_normal(vertices[v]));
    vec3 e = vec3(0.0);
    for (uint l = 0u; l < push.light_count; ++l) {
        if (!light_is_environment(lights[l])) continue;
        vec3 wi, irradiance;
        light_incidence(lights[l], p, wi, irradiance);
        float cos_i = dot(n, wi);
        if (cos_i <= 0.0) continue;
        // Translucent: what the surface transmits, F_t(cos) of it (as splat.comp weighs it),
        // which the shading pass turns into local exitance.
        float fresnel = push.eta > 0.0 ? dipole_fresnel_transmittance(cos_i, push.eta) : 1.0;
        e += irradiance * (cos_i * fresnel * light_visibility(lights[l], shadow_maps, p, n, 1));
    }
    irradiance_out[v] = vec4(e, 0.0);
}

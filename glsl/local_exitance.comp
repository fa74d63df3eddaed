#version 450
// Local exitance: the exitance shading draws for a translucent object's channels the planner
// computes locally, M = R_d,total E_t (render::plan), evaluated at every vertex of one object
// instead of at pixels, so that `--export-exitance` writes what is drawn. E_t is what
// shade.glsl adds up: the environment's transmitted part from the per-vertex cache
// (vertex_light.comp), plus each key light's E cos F_t(cos, eta) V with the shadow filter the
// frame's shading uses. Gathered channels are written too (the same formula); the caller keeps
// the gather's values for them.
//
// Bindings: 0 = vertices (VertexRecord[]), 1 = objects (ObjectRecord[]), 2 = lights (Light[]),
// 3 = shadow maps (sampler2DArrayShadow), 4 = environment irradiance (vec4 per vertex),
// 5 = output (vec4 per vertex), write. Push: LocalExitancePush.
#include "dipole.glsl"
#include "lights.glsl"
#include "scene.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 2) readonly buffer Lights { Light lights[]; };
layout(set = 0, binding = 3) uniform sampler2DArrayShadow shadow_maps;
layout(std430, set = 0, binding = 4) readonly buffer EnvironmentIrradiance { vec4 environment[]; };
layout(std430, set = 0, binding = 5) writeonly buffer LocalExitance { vec4 local_exitance[]; };
struct LocalExitancePush {
    uint first_vertex;      // one dispatch per object: its vertices
    uint vertex_count;
    uint object;
    uint key_light_count;   // the key lights come first in the light buffer
    int shadow_radius;      // 0: one bilinear tap, 1: the four-tap tent (Plan::one_tap_shadows)
};
layout(push_constant) uniform LocalExitancePushBlock { LocalExitancePush push; };

void main() {
    if (gl_GlobalInvocationID.x >= push.vertex_count) return;
    uint v = push.first_vertex + gl_GlobalInvocationID.x;
    ObjectRecord o = objects[push.object];
    vec3 p = vertex_position(vertices[v]);
    vec3 n = normalize(vertex_normal(vertices[v]));
    vec3 transmitted = environment[v].rgb;
    for (uint l = 0u; l < push.key_light_count; ++l) {
        vec3 wi, irradiance;
        light_incidence(lights[l], p, wi, irradiance);
        float cos_i = dot(n, wi);
        if (cos_i <= 0.0) continue;
        float vis = light_visibility(lights[l], shadow_maps, p, n, push.shadow_radius);
        transmitted += irradiance * (cos_i * dipole_fresnel_transmittance(cos_i, o.eta) * vis);
    }
    // R_d,total per channel is the record's albedo (ObjectRecord::new), as shading reads it.
    local_exitance[v] = vec4(o.albedo_roughness.rgb * transmitted, 0.0);
}

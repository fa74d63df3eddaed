#version 450
#extension GL_GOOGLE_include_directive : require
// directional_dipole_eval: evaluates common/directional_dipole.glsl for a buffer of records, so
// tests/optics_gpu.rs can compare the f32 twin with src/optics/directional_dipole.rs.
// Bindings: 0 = vec4[] inputs, seven per record: (D, sigma_tr, d_e, A), (C_phi, C_E, sigma_t',
// strength), x_i, n_i, w_12, x_o, n_o (xyz); 1 = vec4[] outputs, one per record: (exitance per
// flux, real source term, virtual source term, 0). Push constant: record count.
#include "directional_dipole.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Inputs { vec4 inputs[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Outputs { vec4 outputs[]; };
layout(push_constant) uniform Push { uint count; } push;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) return;
    uint b = 7u * i;
    vec4 a = inputs[b];
    vec4 c = inputs[b + 1u];
    DirectionalChannel ch = DirectionalChannel(a.x, a.y, a.z, a.w, c.x, c.y, c.z, c.w);
    vec3 x_i = inputs[b + 2u].xyz;
    vec3 n_i = inputs[b + 3u].xyz;
    vec3 w_12 = inputs[b + 4u].xyz;
    vec3 x_o = inputs[b + 5u].xyz;
    vec3 n_o = inputs[b + 6u].xyz;
    vec2 t = dd_sources(ch, x_i, n_i, w_12, x_o, n_o);
    outputs[i] = vec4(dd_exitance_per_flux(ch, x_i, n_i, w_12, x_o, n_o), t.x, t.y, 0.0);
}

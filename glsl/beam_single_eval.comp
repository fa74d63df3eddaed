#version 450
#extension GL_GOOGLE_include_directive : require
// beam_single_eval: evaluates common/beam_single.glsl for a buffer of records, so
// tests/optics_gpu.rs can compare the f32 twin with src/optics/beam_single.rs.
// Bindings: 0 = vec4[] inputs, five per record: (sigma_s, sigma_t, g, eta), x_i, w_12, x_o, n_o
// (xyz); 1 = vec4[] outputs, one per record: (exitance per flux, 0, 0, 0). Push constant: record
// count.
#include "dipole.glsl"
#include "single_scatter.glsl"
#include "beam_single.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Inputs { vec4 inputs[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Outputs { vec4 outputs[]; };
layout(push_constant) uniform Push { uint count; } push;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) return;
    uint b = 5u * i;
    vec4 c = inputs[b];
    BeamMedium m = BeamMedium(c.x, c.y, c.z, c.w);
    float k = beam_single_exitance_per_flux(m, inputs[b + 1u].xyz, inputs[b + 2u].xyz, inputs[b + 3u].xyz,
        inputs[b + 4u].xyz);
    outputs[i] = vec4(k, 0.0, 0.0, 0.0);
}

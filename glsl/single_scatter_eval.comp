#version 450
#extension GL_GOOGLE_include_directive : require
// single_scatter_eval: evaluates common/single_scatter.glsl for a buffer of parameter records,
// so tests/optics_gpu.rs can compare the f32 twin with src/optics/single_scatter.rs.
// Bindings: 0 = vec4[] inputs (albedo, g, eta, cos_out), 1 = vec4[] outputs (R1, the phase
// function at cos_out, the refracted cosine or 0, 0). Push constant: record count.
#include "dipole.glsl"
#include "single_scatter.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Inputs { vec4 inputs[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Outputs { vec4 outputs[]; };
layout(push_constant) uniform Push { uint count; } push;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) return;
    vec4 p = inputs[i];
    float cos_sq = ss_refracted_cosine_sq(p.w, p.z);
    outputs[i] = vec4(single_scatter_reflectance(p.x, p.y, p.z, p.w), ss_henyey_greenstein(p.w, p.y),
        cos_sq > 0.0 ? sqrt(cos_sq) : 0.0, 0.0);
}

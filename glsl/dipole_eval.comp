#version 450
#extension GL_GOOGLE_include_directive : require
// dipole_eval: evaluates every function of common/dipole.glsl for a buffer of parameter records,
// so tests/optics_gpu.rs can compare the f32 twin with the f64 reference in src/optics/.
// Bindings: 0 = EvalInput[] (read), 1 = EvalOutput[] (write). Push constant: record count.
// Rust mirrors of the records: translucent::optics::gpu::{DipoleEvalInput, DipoleEvalOutput}.
#include "dipole.glsl"

layout(local_size_x = 64) in;

struct EvalInput {
    float sigma_a;        // 1/mm
    float sigma_s_prime;  // 1/mm
    float eta;
    float mm_per_unit;    // scene scale
    float r;              // scene units
    float area;           // scene units^2
    float cos_theta_i;
    float cos_theta_o;
    float t_eta;          // 1 - 2 FM1(eta), from the CPU
    float pad0;
    float pad1;
    float pad2;
};

struct EvalOutput {
    float sigma_t_prime;
    float alpha_prime;
    float sigma_tr;
    float F_dr;
    float A;
    float z_r;
    float z_v;
    float r_d;
    float r_d_total;
    float r_d_disk;       // P(r)
    float kernel;         // dipole_kernel(r, area)
    float near_energy;    // E_near(1.5 sqrt(area))
    float r_d_far;        // R_far(r, 1.5 sqrt(area))
    float r_d_far_cluster; // the cluster kernel at r with tr C = 0.3 r^2, axial variance 0.1 r^2
    float fresnel_r;      // F_r(cos_theta_i, eta)
    float fresnel_t;      // F_t(cos_theta_o, eta)
    float s_d;
    float near_kept_edge; // dipole_near_kept_at_edge(b, t = r)
};

layout(std430, set = 0, binding = 0) readonly buffer Inputs { EvalInput inputs[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Outputs { EvalOutput outputs[]; };
layout(push_constant) uniform Push { uint count; } push;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) return;
    EvalInput p = inputs[i];
    float sigma_a = p.sigma_a * p.mm_per_unit;
    float sigma_s_prime = p.sigma_s_prime * p.mm_per_unit;
    DipoleChannel ch = dipole_channel(sigma_a, sigma_s_prime, p.eta);
    float b = DIPOLE_B_PER_SQRT_AREA * sqrt(p.area);

    EvalOutput o;
    o.sigma_t_prime = sigma_a + sigma_s_prime;
    o.alpha_prime = ch.alpha_prime;
    o.sigma_tr = ch.sigma_tr;
    o.F_dr = dipole_F_dr(p.eta);
    o.A = dipole_A(p.eta);
    o.z_r = ch.z_r;
    o.z_v = ch.z_v;
    o.r_d = dipole_r_d(ch, p.r);
    o.r_d_total = dipole_r_d_total(ch);
    o.r_d_disk = dipole_r_d_disk(ch, p.r);
    o.kernel = dipole_kernel(ch, p.r, p.area);
    o.near_energy = dipole_near_energy(ch, b);
    o.r_d_far = dipole_r_d_far(ch, p.r, b);
    o.r_d_far_cluster = dipole_r_d_far_cluster_sq(ch, p.r * p.r, b * b, 0.3 * p.r * p.r, 0.1 * p.r * p.r);
    o.fresnel_r = dipole_fresnel_reflectance(p.cos_theta_i, p.eta);
    o.fresnel_t = dipole_fresnel_transmittance(p.cos_theta_o, p.eta);
    o.s_d = dipole_s_d(ch, p.eta, p.r, p.cos_theta_i, p.cos_theta_o, p.t_eta);
    o.near_kept_edge = dipole_near_kept_at_edge(ch, b, p.r);
    outputs[i] = o;
}

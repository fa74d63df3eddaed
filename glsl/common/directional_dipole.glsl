// The directional dipole (Frisvad, Hachisuka and Kjeldsen 2014, "Directional Dipole Model for
// Subsurface Scattering", ACM TOG 34(1)): the f32 twin of src/optics/directional_dipole.rs, whose
// module doc gives the formulas and where the coefficients differ from the standard dipole's.
// tests/optics_gpu.rs compares the two. No render pass uses it yet.
//
// Exitance at x_o (outward normal n_o) per unit flux entering at x_i (outward normal n_i) and
// travelling inside along w_12: real ray source minus the virtual one mirrored in the modified
// tangent plane, clamped at 0, times the source strength.

#ifndef DIRECTIONAL_DIPOLE_GLSL
#define DIRECTIONAL_DIPOLE_GLSL

const float DD_PI = 3.14159265358979;

// One channel's coefficients, computed on the CPU (DirectionalDipole's fields).
struct DirectionalChannel {
    float D;             // diffusion coefficient
    float sigma_tr;      // sqrt(sigma_a / D)
    float d_e;           // extrapolation distance 2.131 D / sqrt(alpha')
    float A;             // (1 - C_E) / (2 C_phi)
    float C_phi;         // fluence weight (Fresnel moments from inside)
    float C_E;           // flux weight (Fresnel moments from inside)
    float sigma_t_prime; // reduced extinction
    float strength;      // 1 (the paper) or alpha'
};

// One ray source's exitance per unit flux: x from the source to the exit point, w its direction,
// r the distance the kernel is taken at, n_o the outward normal at the exit point.
float dd_source(DirectionalChannel ch, vec3 x, vec3 w, float r, vec3 n_o) {
    float s = ch.sigma_tr * r;
    float s1 = 1.0 + s;
    float x_w = dot(x, w);
    float r2 = r * r;
    float fluence = r2 / ch.D + 3.0 * s1 * x_w;
    float flux = 3.0 * ch.D * s1 * dot(w, n_o) - (s1 + 3.0 * ch.D * (3.0 * s1 + s * s) / r2 * x_w) * dot(x, n_o);
    // e^-s / (4 pi r^3) as (e^-s / r) / (4 pi r^2): no r^3 to underflow before the exponential.
    return exp(-s) / r / (4.0 * DD_PI * r2) * (ch.C_phi * fluence - ch.C_E * flux);
}

// The real and the virtual source's terms, unclamped, without the strength.
vec2 dd_sources(DirectionalChannel ch, vec3 x_i, vec3 n_i, vec3 w_12, vec3 x_o, vec3 n_o) {
    vec3 x = x_o - x_i;
    float r2 = dot(x, x);
    float r = sqrt(r2);
    vec3 side = cross(n_i, x);
    float side2 = dot(side, side);
    vec3 n_star = (side2 > 1e-12 * r2 && r > 0.0) ? cross(x / r, side * inversesqrt(side2)) : n_i;
    float x_w = dot(x, w_12);
    float cos_beta = -sqrt(max(r2 - x_w * x_w, 0.0) / (r2 + ch.d_e * ch.d_e));
    float mu_0 = -dot(n_o, w_12);
    float d_r;
    if (mu_0 > 0.0) {
        float dm = ch.D * mu_0;
        d_r = sqrt(r2 + dm * (dm - 2.0 * ch.d_e * cos_beta));
    } else {
        float z = 1.0 / (3.0 * ch.sigma_t_prime);
        d_r = sqrt(r2 + z * z);
    }
    vec3 x_v = x_i + n_star * (2.0 * ch.A * ch.d_e);
    vec3 w_v = w_12 - n_star * (2.0 * dot(w_12, n_star));
    vec3 xv = x_o - x_v;
    return vec2(dd_source(ch, x, w_12, d_r, n_o), dd_source(ch, xv, w_v, length(xv), n_o));
}

float dd_exitance_per_flux(DirectionalChannel ch, vec3 x_i, vec3 n_i, vec3 w_12, vec3 x_o, vec3 n_o) {
    vec2 t = dd_sources(ch, x_i, n_i, w_12, x_o, n_o);
    return ch.strength * max(t.x - t.y, 0.0);
}

#endif

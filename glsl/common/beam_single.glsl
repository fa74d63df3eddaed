// Single scattering between two surface points (Jensen et al. 2001, Eq. 3, resolved in space):
// the f32 twin of src/optics/beam_single.rs, whose module doc derives the kernel
//
// K1(x_i, w_12; x_o, n_o) = int_0^inf sigma_s p(cos psi) e^(-sigma_t (t + r)) F_t(cos theta, 1/eta)
//                           cos theta / r^2 dt,   y = x_i + t w_12,  r = |x_o - y|,
//
// the radiant exitance at x_o per unit flux that entered at x_i along w_12. The same rule: t =
// t* + h tan phi (t* the closest approach, h its distance), pieces of phi split at t*, at t* plus
// 4^-4 to 16 mean free paths and where the path crosses the critical angle, 8-point
// Gauss-Legendre per piece (u^2 after a critical break). Needs dipole_fresnel_transmittance
// (include dipole.glsl first) and ss_henyey_greenstein (single_scatter.glsl).

#ifndef BEAM_SINGLE_GLSL
#define BEAM_SINGLE_GLSL

const float BS_HALF_PI = 1.57079632679490;
const float BS_H_MIN = 1e-6;
// The positive half of the 8 Gauss-Legendre nodes on [-1, 1] and their weights.
const float BS_GL_X[4] = float[4](0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363);
const float BS_GL_W[4] = float[4](0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763);

struct BeamMedium {
    float sigma_s;
    float sigma_t;
    float g;
    float eta;
};

float bs_integrand(BeamMedium m, float phi, float t_star, float h, vec3 d, vec3 w, vec3 n_o) {
    float t = max(t_star + h * tan(phi), 0.0);
    vec3 v = d - t * w;
    float r = length(v);
    if (!(r > 0.0)) return 0.0;
    float cos_theta = dot(v, n_o) / r;
    if (!(cos_theta > 0.0)) return 0.0;
    float travel = m.sigma_t * (t + r);
    if (travel > 80.0) return 0.0;
    return ss_henyey_greenstein(dot(w, v) / r, m.g) * exp(-travel)
        * dipole_fresnel_transmittance(min(cos_theta, 1.0), 1.0 / m.eta) * cos_theta;
}

// Up to two distances t >= 0 where (d - t w) . n = mu_c |d - t w| (see the f64's
// critical_distances); NaN where there is none.
vec2 bs_critical_distances(BeamMedium m, vec3 d, vec3 w, vec3 n) {
    vec2 roots = vec2(0.0 / 0.0);
    if (!(m.eta > 1.0)) return roots;
    float mu_sq = 1.0 - 1.0 / (m.eta * m.eta);
    float a = dot(d, n), b = dot(w, n), c = dot(d, d), e = dot(d, w);
    float qa = b * b - mu_sq, qb = 2.0 * (mu_sq * e - a * b), qc = a * a - mu_sq * c;
    float disc = qb * qb - 4.0 * qa * qc;
    if (disc < 0.0 || abs(qa) <= 1e-12) return roots;
    float q = -0.5 * (qb + (qb < 0.0 ? -1.0 : 1.0) * sqrt(disc));
    roots = vec2(q / qa, q != 0.0 ? qc / q : 0.0 / 0.0);
    for (int k = 0; k < 2; ++k) {
        if (!(roots[k] >= 0.0 && a - roots[k] * b > 0.0)) roots[k] = 0.0 / 0.0;
    }
    return roots;
}

float beam_single_exitance_per_flux(BeamMedium m, vec3 x_i, vec3 w_12, vec3 x_o, vec3 n_o) {
    vec3 d = x_o - x_i;
    float t_star = dot(d, w_12);
    float mfp = 1.0 / m.sigma_t;
    float h = max(length(d - t_star * w_12), BS_H_MIN * mfp);
    float start = atan((0.0 - t_star) / h);
    // Breaks in phi, in order; kinks[p]: the transmittance starts at breaks[p] as a square root.
    float breaks[12];
    bool kinks[12];
    int count = 0;
    breaks[count] = start; kinks[count] = false; count++;
    breaks[count] = BS_HALF_PI; kinks[count] = false; count++;
    float steps[8] = float[8](0.0, 1.0 / 256.0, 1.0 / 64.0, 1.0 / 16.0, 0.25, 1.0, 4.0, 16.0);
    vec2 critical = bs_critical_distances(m, d, w_12, n_o);
    for (int k = 0; k < 10; ++k) {
        float t = k < 8 ? t_star + steps[k] * mfp : critical[k - 8];
        if (isnan(t)) continue;
        float phi = atan((t - t_star) / h);
        if (phi > start && phi < BS_HALF_PI) {
            // Insertion in order.
            int j = count;
            while (j > 0 && breaks[j - 1] > phi) { breaks[j] = breaks[j - 1]; kinks[j] = kinks[j - 1]; j--; }
            breaks[j] = phi; kinks[j] = k >= 8; count++;
        }
    }
    float sum = 0.0;
    for (int p = 0; p + 1 < count; ++p) {
        float a = breaks[p], b = breaks[p + 1];
        for (int k = 0; k < 8; ++k) {
            float x = k < 4 ? -BS_GL_X[3 - k] : BS_GL_X[k - 4];
            float w = k < 4 ? BS_GL_W[3 - k] : BS_GL_W[k - 4];
            float u = 0.5 * (x + 1.0);
            float phi = kinks[p] ? a + (b - a) * u * u : a + (b - a) * u;
            float jacobian = kinks[p] ? (b - a) * u * w : 0.5 * (b - a) * w;
            sum += jacobian * bs_integrand(m, phi, t_star, h, d, w_12, n_o);
        }
    }
    return m.sigma_s * sum / h;
}

#endif

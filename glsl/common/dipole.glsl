// dipole.glsl: the dipole diffusion model in f32, twin of the f64 reference in src/optics/
// (dipole.rs, fresnel.rs, kernel.rs; the doc comments there give the derivations). Every function
// here has a same-named counterpart there, and tests/optics_gpu.rs compares them.
//
// Written to stay finite for everything a validated Material yields (sigma_t' per scene unit in
// [1e-12, 1e12], eta in [1/3, 3]) and distances up to 1e18 scene units:
// - sigma_a = 0 gives sigma_tr = 0, alpha' = 1 and exp(0) terms, no division by sigma_tr;
// - products are ordered as ratios <= 1 ((z/d) before 1/d) so nothing overflows;
// - 1 - e^-x uses a series for small x, differences of nearly equal terms are rewritten as sums
//   of non-negative terms (ring integrals, second differences), so no catastrophic cancellation;
// - exp of large negatives underflows to 0, which is the right answer.
#ifndef TRANSLUCENT_DIPOLE_GLSL
#define TRANSLUCENT_DIPOLE_GLSL

const float DIPOLE_PI = 3.14159265358979;

// One colour channel's dipole constants, lengths in scene units (Rust: DipoleChannelGpu).
struct DipoleChannel {
    float alpha_prime; // reduced albedo sigma_s' / sigma_t'
    float sigma_tr;    // effective transport coefficient sqrt(3 sigma_a sigma_t')
    float z_r;         // real source depth 1 / sigma_t'
    float z_v;         // virtual source height z_r + 4 A D
};

// ---- Fresnel (src/optics/fresnel.rs) ----

// Exact unpolarized dielectric reflectance; eta = n_t / n_i. TIR gives 1, eta = 1 gives 0.
float dipole_fresnel_reflectance(float cos_theta_i, float eta) {
    if (eta == 1.0) return 0.0;
    float cos_i = min(abs(cos_theta_i), 1.0);
    // cos^2 theta_t without the 1 - sin^2 cancellation at grazing incidence.
    float cos_t_sq = (cos_i * cos_i + (eta - 1.0) * (eta + 1.0)) / (eta * eta);
    if (cos_t_sq <= 0.0) return 1.0;
    float cos_t = sqrt(cos_t_sq);
    float r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5 * (r_s * r_s + r_p * r_p);
}

float dipole_fresnel_transmittance(float cos_theta_i, float eta) {
    return 1.0 - dipole_fresnel_reflectance(cos_theta_i, eta);
}

// Diffuse Fresnel reflectance fits (Jensen et al. 2001 after Egan & Hilgeman; docs/optics.md,
// "Per colour channel"),
// the same polynomials expanded about eta = 1, where their terms cancel to 0.0016 (see F_dr in
// fresnel.rs).
float dipole_F_dr(float eta) {
    if (eta >= 1.0) {
        float u = eta - 1.0;
        return (0.0016 + u * (2.2368 + u * (0.8588 + u * 0.0636))) / (eta * eta);
    }
    float w = 1.0 / eta - 1.0;
    return 0.0017 + w * (0.2369 + w * (-0.1411 + w * 0.0636));
}

float dipole_A(float eta) {
    float f = dipole_F_dr(eta);
    return (1.0 + f) / (1.0 - f);
}

// ---- The dipole (src/optics/dipole.rs) ----

// 1 - e^-x for x >= 0, accurate to a few ulp also for small x (GLSL has no expm1).
float dipole_one_minus_exp(float x) {
    if (x < 0.1) {
        return x * (1.0 - x / 2.0 * (1.0 - x / 3.0 * (1.0 - x / 4.0 * (1.0 - x / 5.0 * (1.0 - x / 6.0)))));
    }
    return 1.0 - exp(-x);
}

// The channel from coefficients per scene unit. sigma_t' = 0 (no medium) yields zeros, so every
// function below returns 0 for it instead of dividing by zero.
DipoleChannel dipole_channel(float sigma_a, float sigma_s_prime, float eta) {
    float sigma_t_prime = sigma_a + sigma_s_prime;
    if (!(sigma_t_prime > 0.0)) return DipoleChannel(0.0, 0.0, 1.0, 1.0);
    float one_minus_alpha_prime = sigma_a / sigma_t_prime;
    float z_r = 1.0 / sigma_t_prime;
    // eta outside the fits' range is refused on the CPU; clamp so a stray value stays finite.
    float a = dipole_A(clamp(eta, 1.0 / 3.0, 3.0));
    return DipoleChannel(sigma_s_prime / sigma_t_prime,
                         sigma_t_prime * sqrt(3.0 * one_minus_alpha_prime),
                         z_r,
                         z_r * (1.0 + 4.0 * a / 3.0));
}

// One pole of seed Eq. 8 at squared distance d_sq: z (sigma_tr + 1/d) e^(-sigma_tr d) / d^2.
float dipole_pole(float z, float s, float d_sq) {
    float d = sqrt(d_sq);
    float inv_d = 1.0 / d;
    return (z * inv_d) * (s + inv_d) * inv_d * exp(-s * d);
}

// Diffuse reflectance profile R_d(r), seed Eq. 8.
float dipole_r_d(DipoleChannel ch, float r) {
    float r_sq = r * r;
    return ch.alpha_prime / (4.0 * DIPOLE_PI)
        * (dipole_pole(ch.z_r, ch.sigma_tr, r_sq + ch.z_r * ch.z_r)
         + dipole_pole(ch.z_v, ch.sigma_tr, r_sq + ch.z_v * ch.z_v));
}

// Total diffuse reflectance (alpha'/2)(e^(-sigma_tr z_r) + e^(-sigma_tr z_v)), which is the closed
// form of R_d,total in docs/optics.md ("Reflectance profile, its integrals, and the BSSRDF")
// since sigma_tr z_r = sqrt(3(1 - alpha')) and z_v = z_r (1 + 4A/3).
float dipole_r_d_total(DipoleChannel ch) {
    return 0.5 * ch.alpha_prime * (exp(-ch.sigma_tr * ch.z_r) + exp(-ch.sigma_tr * ch.z_v));
}

// One pole's ring integral z [e^(-s d1)/d1 - e^(-s d2)/d2], rewritten without cancellation.
float dipole_ring_term(float z, float s, float r1_sq, float delta_sq) {
    float d1 = sqrt(r1_sq + z * z);
    float d2 = sqrt(r1_sq + delta_sq + z * z);
    float gap = delta_sq / (d1 + d2);
    return (z / d1) * exp(-s * d1) * (gap / d2 + (d1 / d2) * dipole_one_minus_exp(s * gap));
}

// Integral of R_d 2 pi r dr between radii sqrt(r1_sq) and sqrt(r1_sq + delta_sq).
float dipole_r_d_ring_sq(DipoleChannel ch, float r1_sq, float delta_sq) {
    return 0.5 * ch.alpha_prime
        * (dipole_ring_term(ch.z_r, ch.sigma_tr, r1_sq, delta_sq)
         + dipole_ring_term(ch.z_v, ch.sigma_tr, r1_sq, delta_sq));
}

// Exact disk integral P(R) of R_d (docs/optics.md, "Reflectance profile, its integrals, and the
// BSSRDF").
float dipole_r_d_disk(DipoleChannel ch, float radius) {
    return dipole_r_d_ring_sq(ch, 0.0, radius * radius);
}

// BSSRDF S_d (seed Eq. 9), normalized by t_eta = 1 - 2 FM1(eta) (computed on the CPU) so that
// the outgoing radiance integrates to the exitance; see Dipole::s_d.
float dipole_s_d(DipoleChannel ch, float eta, float r, float cos_theta_i, float cos_theta_o, float t_eta) {
    return dipole_fresnel_transmittance(cos_theta_i, eta) * dipole_r_d(ch, r)
        * dipole_fresnel_transmittance(cos_theta_o, eta) / (DIPOLE_PI * t_eta);
}

// ---- The near-field kernel (src/optics/kernel.rs, whose module doc explains the design) ----

// DIPOLE_B_PER_SQRT_AREA, DIPOLE_BUMP_DELTA, DIPOLE_REMAINDER_*, DIPOLE_NEAR_BLEND_RADIUS:
// generated by build.rs from src/optics/kernel_constants.rs.
#include "kernel_constants.glsl"

// One pole of R_far: p(D + beta) - beta p'(D + beta), D + beta = r^2 + z^2 + b^2 = dd_sq, beta = b^2.
float dipole_far_pole(float z, float s, float dd_sq, float beta) {
    float inv_d = inversesqrt(dd_sq);
    float d = dd_sq * inv_d;
    float q = beta * inv_d * inv_d; // <= 1
    return (z * inv_d) * inv_d * exp(-s * d) * (s + inv_d + 0.5 * q * (s * s * d + 3.0 * s + 3.0 * inv_d));
}

// R_far(r) = R_b(r) - b^2 dR_b/d(b^2), from r^2 and b^2 (kernel::r_d_far).
float dipole_r_d_far_sq(DipoleChannel ch, float r_sq, float beta) {
    return ch.alpha_prime / (4.0 * DIPOLE_PI)
        * (dipole_far_pole(ch.z_r, ch.sigma_tr, r_sq + beta + ch.z_r * ch.z_r, beta)
         + dipole_far_pole(ch.z_v, ch.sigma_tr, r_sq + beta + ch.z_v * ch.z_v, beta));
}

// The far kernel of a cluster, to second order in its spread (kernel::r_d_far_cluster): tr_cov
// is the trace of the power-weighted covariance C of its members about the centroid, axial_cov
// the variance along the direction to the receiver; r_sq the squared distance to the centroid.
float dipole_far_cluster_pole(float z, float s, float r_sq, float dd_sq, float beta, float tr_cov, float axial_cov) {
    float inv_d = inversesqrt(dd_sq);
    float d = dd_sq * inv_d;
    float q = beta * inv_d * inv_d;
    float sd = s * d;
    float far = s + inv_d + 0.5 * q * (s * s * d + 3.0 * s + 3.0 * inv_d);
    float u = tr_cov * inv_d * inv_d;
    float v = axial_cov * (inv_d * inv_d) * (r_sq * inv_d * inv_d);
    float spread = 0.5 * (-(sd * sd + 3.0 * sd + 3.0) * u + (((sd + 6.0) * sd + 15.0) * sd + 15.0) * v);
    return (z * inv_d) * inv_d * exp(-sd) * (far + spread * inv_d);
}

float dipole_r_d_far_cluster_sq(DipoleChannel ch, float r_sq, float beta, float tr_cov, float axial_cov) {
    return ch.alpha_prime / (4.0 * DIPOLE_PI)
        * (dipole_far_cluster_pole(ch.z_r, ch.sigma_tr, r_sq, r_sq + beta + ch.z_r * ch.z_r, beta, tr_cov, axial_cov)
         + dipole_far_cluster_pole(ch.z_v, ch.sigma_tr, r_sq, r_sq + beta + ch.z_v * ch.z_v, beta, tr_cov, axial_cov));
}

float dipole_r_d_far(DipoleChannel ch, float r, float b) {
    return dipole_r_d_far_sq(ch, r * r, b * b);
}

// G(z^2) - G(z^2 + beta) + beta G'(z^2 + beta), G(D) = z e^(-s sqrt(D)) / sqrt(D)
// (kernel::taylor_remainder).
float dipole_taylor_remainder(float z, float s, float beta) {
    float d1 = sqrt(z * z + beta);
    float gap = beta / (z + d1);
    if (gap <= DIPOLE_REMAINDER_MAX_SPREAD * z && s * gap <= DIPOLE_REMAINDER_MAX_DECAY) {
        const float X[5] = float[5](-0.906179845938664, -0.538469310105683, 0.0, 0.538469310105683, 0.906179845938664);
        const float W[5] = float[5](0.236926885056189, 0.478628670499366, 0.568888888888889, 0.478628670499366, 0.236926885056189);
        float sum = 0.0;
        for (int k = 0; k < 5; ++k) {
            float y = 0.5 * beta * (1.0 + X[k]);
            float q_sq = z * z + y;
            float q = sqrt(q_sq);
            float sq = s * q;
            sum += W[k] * (y / q_sq) * (beta / q_sq) * (z / q) * exp(-sq) * (sq * sq + 3.0 * sq + 3.0);
        }
        return 0.125 * sum;
    }
    float q = beta / (d1 * d1);
    return exp(-s * z) * (1.0 - (z / d1) * exp(-s * gap) * (1.0 + 0.5 * q * (s * d1 + 1.0)));
}

// E_near(b) = R_d,total - integral R_far 2 pi r dr: the light a sample keeps on its footprint.
// Depends only on the channel and the sample's area: a splat pass can compute it once per sample.
float dipole_near_energy(DipoleChannel ch, float b) {
    float beta = b * b;
    return 0.5 * ch.alpha_prime
        * (dipole_taylor_remainder(ch.z_r, ch.sigma_tr, beta) + dipole_taylor_remainder(ch.z_v, ch.sigma_tr, beta));
}

// The near energy farther than `radius` from its receiver, integral_{r > R} R_near 2 pi r dr:
// each pole's Taylor remainder taken at R^2 + z^2 (kernel::near_tail).
float dipole_near_tail(DipoleChannel ch, float beta, float radius) {
    float qr = sqrt(radius * radius + ch.z_r * ch.z_r);
    float qv = sqrt(radius * radius + ch.z_v * ch.z_v);
    return 0.5 * ch.alpha_prime
        * ((ch.z_r / qr) * dipole_taylor_remainder(qr, ch.sigma_tr, beta)
           + (ch.z_v / qv) * dipole_taylor_remainder(qv, ch.sigma_tr, beta));
}

// The fraction of E_near(b) a receiver keeps when an open boundary passes t from it:
// 1 - (1 / pi E_near) integral_0^inf T(t cosh v) / cosh v dv, in panels of at most one unit of
// v, 4-point Gauss-Legendre each (kernel::near_kept_at_edge).
float dipole_near_kept_at_edge(DipoleChannel ch, float b, float t) {
    float beta = b * b;
    float ell = sqrt(ch.z_v * ch.z_v + beta);
    if (isnan(t) || t >= DIPOLE_NEAR_EDGE_REACH * ell || b <= 0.0) return 1.0;
    float total = dipole_near_tail(ch, beta, 0.0);
    if (total <= 0.0) return 1.0;
    if (t <= DIPOLE_NEAR_EDGE_TOUCH * ell) return 0.5;
    float ratio = DIPOLE_NEAR_EDGE_REACH * ell / t;
    float v_max = log(ratio + sqrt(ratio * ratio - 1.0)); // acosh, written out for large ratios
    float panels = clamp(ceil(v_max), 1.0, DIPOLE_NEAR_EDGE_PANELS);
    float h = v_max / panels;
    const float X[2] = float[2](0.339981043584856, 0.861136311594053);
    const float W[2] = float[2](0.652145154862546, 0.347854845137454);
    float sum = 0.0;
    for (float p = 0.0; p < panels; p += 1.0) {
        float centre = (p + 0.5) * h;
        for (int k = 0; k < 2; ++k) {
            for (int side = -1; side <= 1; side += 2) {
                float v = centre + float(side) * 0.5 * h * X[k];
                float c = cosh(v);
                sum += W[k] * dipole_near_tail(ch, beta, t * c) / c;
            }
        }
    }
    float missing = 0.5 * h * sum / DIPOLE_PI;
    return clamp(1.0 - missing / total, 0.0, 1.0);
}

// Footprint weight w(r / rho): 1 inside, smoothstep edge, integral w 2 pi r dr = dA. Computed
// as S(1 - t), not 1 - S(t), so the tiny values near the outer edge keep their digits.
float dipole_footprint_weight(float x) {
    float c = sqrt(1.0 - DIPOLE_BUMP_DELTA * DIPOLE_BUMP_DELTA / 5.0);
    float t = clamp((c + DIPOLE_BUMP_DELTA - x) / (2.0 * DIPOLE_BUMP_DELTA), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

float dipole_point_kernel(DipoleChannel ch, float r, float area) {
    return dipole_r_d(ch, r) * area;
}

// The far part alone (kernel::far_kernel): the gather adds the near energy through a blend
// over neighbouring samples instead of each sample's own disk (see far_kernel's doc).
float dipole_far_kernel(DipoleChannel ch, float r, float area) {
    if (!(area > 0.0)) return 0.0;
    return area * dipole_r_d_far_sq(ch, r * r, DIPOLE_B_PER_SQRT_AREA * DIPOLE_B_PER_SQRT_AREA * area);
}

// The kernel with the sample's near energy e_near = dipole_near_energy(ch, 1.5 sqrt(area))
// computed beforehand.
float dipole_kernel_with_near_energy(DipoleChannel ch, float r, float area, float e_near) {
    if (!(area > 0.0)) return 0.0;
    float rho = sqrt(area / DIPOLE_PI);
    return dipole_far_kernel(ch, r, area) + e_near * dipole_footprint_weight(r / rho);
}

// What a sample of area `area` contributes to the exitance of a receiver at distance r, per unit
// flux density at the sample (dimensionless).
float dipole_kernel(DipoleChannel ch, float r, float area) {
    if (!(area > 0.0)) return 0.0;
    return dipole_kernel_with_near_energy(ch, r, area, dipole_near_energy(ch, DIPOLE_B_PER_SQRT_AREA * sqrt(area)));
}


// Shepard weight (1 - (r/R)^2)^3 inside R = k sqrt(area) (kernel::near_blend_weight).
float dipole_near_blend_weight(float r, float area, float k) {
    float radius = k * sqrt(max(area, 0.0));
    if (!(r < radius)) return 0.0;
    float x = r / radius;
    float t = 1.0 - x * x;
    return t * t * t;
}

#endif // TRANSLUCENT_DIPOLE_GLSL

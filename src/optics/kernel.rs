//! The near-field kernel of the discrete dipole sum (seed Eq. 11).
//!
//! The seed turns the integral of Eq. 10 into a sum over sample points, each standing for an
//! area `dA`: exitance at a receiver = sum over samples of `E_i K(r_i, dA_i)`. The point kernel
//! `K = R_d(r) dA` is right far from a sample, but `R_d` has a peak of width `z_r` and a `1/r^3`
//! flank out to the diffusion length; when these are not much wider than the sample spacing,
//! point values overstate what the footprints really reflect (a uniformly lit plane of samples
//! reflects up to 1e9 times what it receives), see `tests/optics.rs`.
//!
//! # Design: a smooth far part, point-sampled, plus the rest of the energy in the footprint
//!
//! Split `R_d = R_far + R_near` with `R_far` smooth on the scale of the spacing, so that point
//! samples of it sum to its integral, and give the rest, `E_near = R_d,total - integral R_far`,
//! to the sample's own footprint:
//!
//! ```text
//! K(r) = dA R_far(r) + E_near w(r / rho),            rho = sqrt(dA / pi),  b = 1.5 sqrt(dA)
//! R_far(r) = 2 R_b(r) - R_{sqrt2 b}(r)
//! R_b(r) = R_d(r) of seed Eq. 8 with every d^2 = r^2 + z^2 replaced by r^2 + z^2 + b^2
//! E_near = (alpha'/2) sum_{z = z_r, z_v} [e^(-sigma_tr z) - 2 z e^(-sigma_tr d1)/d1 + z e^(-sigma_tr d2)/d2]
//!          with d1 = sqrt(z^2 + b^2), d2 = sqrt(z^2 + 2 b^2)
//! ```
//!
//! Why each piece:
//! - `R_b` moves the singularities of `R_d` (at `r = +-i z`) out to `+-i sqrt(z^2 + b^2)`, so its
//!   point samples on a lattice of spacing `h` sum to its integral up to roughly
//!   `4 e^(-2 pi b / h)` (Poisson summation), 3e-4 for `b = 1.5 h`, whatever `z_r` and the
//!   diffusion length are (the plane test measures at most 2.1e-4). The combination `2 R_b - R_{sqrt2 b}` (Richardson in `b^2`) cancels the
//!   `O(b^2)` change, so `R_far = R_d (1 + O(b^4/r^4))` away from the footprint.
//! - `integral R_b 2 pi r dr = (alpha'/2) sum_z z e^(-sigma_tr d1)/d1` by the same antiderivative
//!   as the exact disk integral ([`crate::optics::Dipole::r_d_disk`]; docs/optics.md,
//!   "Reflectance profile, its integrals, and the BSSRDF"), so `E_near` is exact and closed-form.
//!   It is a second difference of `z e^(-sigma_tr sqrt(D))/sqrt(D)` in `D`, which is completely
//!   monotone, so `R_near >= 0` and `E_near >= 0`. When `b << z` it cancels catastrophically;
//!   there it is evaluated as the integral of the second derivative ([`second_difference`]).
//! - `w` is the footprint: 1 inside, 0 outside, with a smoothstep edge of half-width
//!   `BUMP_DELTA rho` centred so that `integral w 2 pi r dr = dA` exactly. It ends at
//!   `1.244 rho`, short of any neighbour at the sample spacing (`>= 1.77 rho`), so each sample's
//!   near energy stays on its own footprint.
//!
//! Together: `integral K 2 pi r dr = dA R_d,total` exactly for every `dA` (the far blend below
//! changes that by under 2e-4, tested); at its own centre a
//! sample returns `K(0) = E_near + dA R_far(0)`, which tends to the disk integral
//! `P(rho) -> R_d,total` when the spacing is much larger than the diffusion length and to
//! `dA R_d(0)` when it is much smaller than `z_r`.
//!
//! # The far blend
//!
//! From `FAR_BLEND_START b` to `FAR_BLEND_END b` the kernel blends (smoothstep in `r`) into the
//! point kernel `R_d(r) dA`, which it is alone beyond; there `R_far` and `R_d` differ by under
//! 1e-3 of `R_d`, so nothing visible or measurable changes, and the GPU evaluates two
//! exponentials per channel instead of four for the bulk of the pairs.
//!
//! Every formula has an f32 twin in `glsl/common/dipole.glsl`; both stay finite for all inputs
//! a validated [`crate::optics::Material`] produces.

use super::Dipole;
use std::f64::consts::PI;

/// Defines each constant of `kernel_constants.rs` as `pub const NAME: f64` (build.rs reads the
/// same file for the GLSL twin).
macro_rules! kernel_constants {
    ($($(#[$doc:meta])* $name:ident = $value:expr;)*) => { $($(#[$doc])* pub const $name: f64 = $value;)* };
}
include!("kernel_constants.rs");

/// The point kernel `R_d(r) dA` of the seed's discrete sum (seed Eq. 11 with Eq. 8): right far
/// from a sample, wrong near it when `z_r` or the diffusion length is small next to the spacing.
pub fn point_kernel(dipole: &Dipole, r: f64, area: f64) -> f64 {
    dipole.r_d(r) * area
}

/// `R_b(r)`: seed Eq. 8 with every `d^2 = r^2 + z^2` replaced by `r^2 + z^2 + b^2`. Each pole is
/// evaluated as `(z/d)(1/d)(sigma_tr + 1/d) e^(-sigma_tr d)` so nothing overflows.
pub fn r_d_regularized(dipole: &Dipole, r: f64, b: f64) -> f64 {
    let rb_sq = r * r + b * b;
    let pole = |z: f64| {
        let d = (rb_sq + z * z).sqrt();
        let inv_d = 1.0 / d;
        (z * inv_d) * inv_d * (dipole.sigma_tr + inv_d) * (-dipole.sigma_tr * d).exp()
    };
    dipole.alpha_prime / (4.0 * PI) * (pole(dipole.z_r) + pole(dipole.z_v))
}

/// The far part `R_far(r) = 2 R_b(r) - R_{sqrt2 b}(r) >= R_b(r) > 0` (see the module doc).
pub fn r_d_far(dipole: &Dipole, r: f64, b: f64) -> f64 {
    2.0 * r_d_regularized(dipole, r, b) - r_d_regularized(dipole, r, std::f64::consts::SQRT_2 * b)
}

/// The near energy `E_near(b) = R_d,total - integral R_far 2 pi r dr >= 0`, in closed form (see
/// the module doc), evaluated without cancellation.
pub fn near_energy(dipole: &Dipole, b: f64) -> f64 {
    let beta = b * b;
    0.5 * dipole.alpha_prime
        * (second_difference(dipole.z_r, dipole.sigma_tr, beta) + second_difference(dipole.z_v, dipole.sigma_tr, beta))
}

/// `z [g(z^2) - 2 g(z^2 + beta) + g(z^2 + 2 beta)]` with `g(D) = e^(-s sqrt(D)) / sqrt(D)`.
///
/// When the three points are close (`(d2 - z)/z <= 0.1` and `s (d2 - z) <= 0.5`) the terms agree
/// to many digits, so instead we integrate: the second difference equals
/// `integral_0^(2 beta) min(y, 2 beta - y) g''(z^2 + y) dy`, with
/// `g''(D) = e^(-s q) (s^2 q^2 + 3 s q + 3) / (4 q^5)`, `q = sqrt(D)`, by 3-point Gauss-Legendre
/// on each half (the integrand is smooth there; error below 1e-8). Each factor is formed as a
/// ratio `<= 1` so nothing overflows in f32. Otherwise it is the difference of two first
/// differences, each free of cancellation (see [`crate::optics::dipole::ring_term`]).
pub fn second_difference(z: f64, s: f64, beta: f64) -> f64 {
    let d1 = (z * z + beta).sqrt();
    let d2 = (z * z + 2.0 * beta).sqrt();
    let spread = 2.0 * beta / (z + d2); // d2 - z without cancellation
    if spread <= SECOND_DIFF_MAX_SPREAD * z && s * spread <= SECOND_DIFF_MAX_DECAY {
        const X: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4]; // sqrt(3/5)
        const W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
        // z beta y g''(z^2 + y) = (y/q^2)(beta/q^2)(z/q) e^(-s q)(s^2 q^2 + 3 s q + 3)/4
        let term = |y: f64, weight: f64| {
            let q_sq = z * z + y;
            let q = q_sq.sqrt();
            let sq = s * q;
            (weight / q_sq) * (beta / q_sq) * (z / q) * (-sq).exp() * (sq * sq + 3.0 * sq + 3.0) * 0.25
        };
        let mut sum = 0.0;
        for k in 0..3 {
            let y = 0.5 * beta * (1.0 + X[k]);
            sum += W[k] * (term(y, y) + term(beta + y, beta - y));
        }
        0.5 * sum
    } else {
        // Gaps between the square roots as beta / (sum), not by subtraction.
        first_difference(z, s, z, d1, beta / (z + d1)) - first_difference(z, s, d1, d2, beta / (d1 + d2))
    }
}

/// `z [e^(-s da)/da - e^(-s db)/db]` for `da <= db = da + gap`, free of cancellation: the form
/// of [`crate::optics::dipole::ring_term`],
/// `(z/da) e^(-s da) [gap/db + (da/db)(1 - e^(-s gap))]`.
fn first_difference(z: f64, s: f64, da: f64, db: f64, gap: f64) -> f64 {
    (z / da) * (-s * da).exp() * (gap / db + (da / db) * -(-s * gap).exp_m1())
}

/// The footprint weight `w(x)`, `x = r / rho`: 1 inside, a smoothstep edge of half-width
/// [`BUMP_DELTA`] centred at `c = sqrt(1 - delta^2 / 5)`, so that `integral w(x) 2x dx = 1`
/// (the edge's derivative is a Beta(2,2) bump of variance `delta^2 / 5`).
///
/// Written as `S((c + delta - x) / (2 delta))` rather than `1 - S(...)` (equal, since
/// `S(t) + S(1 - t) = 1`) so that near the outer edge, where `w` is tiny and multiplies the
/// whole near energy, f32 keeps its relative precision.
pub fn footprint_weight(x: f64) -> f64 {
    let c = (1.0 - BUMP_DELTA * BUMP_DELTA / 5.0).sqrt();
    smoothstep((c + BUMP_DELTA - x) / (2.0 * BUMP_DELTA))
}

/// The kernel of the discrete dipole sum: what a sample of area `area` (scene units squared)
/// contributes to the radiant exitance of a receiver at distance `r`, per unit of flux density
/// (transmitted irradiance) at the sample. Dimensionless. See the module doc for its design.
/// Zero for a sample of zero area.
pub fn footprint_kernel(dipole: &Dipole, r: f64, area: f64) -> f64 {
    if area <= 0.0 {
        return 0.0;
    }
    // The footprint ends at 1.244 rho, far inside the start of the far blend (8 b = 13.5 rho),
    // so the near energy adds to the far kernel without touching its blend.
    let b = B_PER_SQRT_AREA * area.sqrt();
    let rho = (area / PI).sqrt();
    far_kernel(dipole, r, area) + near_energy(dipole, b) * footprint_weight(r / rho)
}

/// The far part of [`footprint_kernel`] alone: `dA R_far(r)` blended into the point kernel
/// beyond `FAR_BLEND_START b`, without the footprint's near energy.
///
/// # Why the renderer gathers with this plus a blended near field
///
/// [`footprint_kernel`] puts each sample's near energy on a disk of area `dA` around it. Summed
/// at the samples themselves that is exact, but a receiver *between* samples (a mesh vertex, a
/// pixel) falls in the gaps between the disks and gets only the far part: under a uniform light
/// the surface shows bright dots at the samples (up to 80% of the light is "near" when the
/// diffusion length is close to the spacing). So the gather splits the sum:
///
/// ```text
/// M(x) = sum_i E_i far_kernel(r_i, A_i)  +  sum_i phi_i(x) E_i E_near,i / sum_i phi_i(x)
/// ```
///
/// The second term interpolates the samples' near exitance `E_i E_near,i` with a partition of
/// unity (Shepard weights [`near_blend_weight`], falling back to the nearest sample where no
/// weight reaches): under uniform light it is `E E_near` at every point, so every receiver gets
/// `E R_d,total`; its integral over the surface is `sum_i E_i E_near,i A_i` up to how well the
/// weights' shares match the samples' (Voronoi) areas.
pub fn far_kernel(dipole: &Dipole, r: f64, area: f64) -> f64 {
    if area <= 0.0 {
        return 0.0;
    }
    let b = B_PER_SQRT_AREA * area.sqrt();
    let (start, end) = (FAR_BLEND_START * b, FAR_BLEND_END * b);
    if r >= end {
        return point_kernel(dipole, r, area);
    }
    let far = area * r_d_far(dipole, r, b);
    if r <= start {
        return far;
    }
    far + smoothstep((r - start) / (end - start)) * (point_kernel(dipole, r, area) - far)
}

/// Shepard weight of a sample in the near-field blend at distance `r`: `(1 - (r/R)^2)^3` inside
/// `R = NEAR_BLEND_RADIUS sqrt(dA)`, 0 outside; smooth (C2) at the rim.
pub fn near_blend_weight(r: f64, area: f64) -> f64 {
    let radius = NEAR_BLEND_RADIUS * area.max(0.0).sqrt();
    if r.is_nan() || r >= radius {
        return 0.0;
    }
    let t = 1.0 - (r / radius) * (r / radius);
    t * t * t
}

/// `3t^2 - 2t^3` on `[0, 1]`, clamped: a blend weight with zero slope at both ends.
pub fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

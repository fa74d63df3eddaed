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
//! to the sample's own footprint. Write each pole of seed Eq. 8 as a function of `D = r^2 + z^2`,
//! `p_z(D) = z (sigma_tr + 1/d) e^(-sigma_tr d) / d^2` with `d = sqrt(D)`, and
//! `G_z(D) = z e^(-sigma_tr d) / d`, whose plane integral it is (`integral p_z(r^2 + z^2) r dr`
//! over `r > R` is `G_z(R^2 + z^2)`, the antiderivative of the exact disk integral,
//! [`crate::optics::Dipole::r_d_disk`]; docs/optics.md, "Reflectance profile, its integrals, and
//! the BSSRDF"). Then, with `beta = b^2`:
//!
//! ```text
//! K(r) = dA R_far(r) + E_near w(r / rho),            rho = sqrt(dA / pi),  b = 1.5 sqrt(dA)
//! R_far(r) = (alpha'/4 pi) sum_{z = z_r, z_v} [p_z(D + beta) - beta p_z'(D + beta)]
//!          = (alpha'/4 pi) sum_z (z/d)(1/d) e^(-sigma_tr d) [sigma_tr + 1/d + (beta/2d^2)(sigma_tr^2 d + 3 sigma_tr + 3/d)],
//!            d = sqrt(r^2 + z^2 + beta)
//! E_near = (alpha'/2) sum_z [G_z(z^2) - G_z(z^2 + beta) + beta G_z'(z^2 + beta)]
//!        = (alpha'/2) sum_z [e^(-sigma_tr z) - (z/d1) e^(-sigma_tr d1) (1 + (beta/2d1^2)(sigma_tr d1 + 1))],
//!            d1 = sqrt(z^2 + beta)
//! ```
//!
//! Why each piece:
//! - `p_z(D + beta)` is the profile regularised by `b` (Eq. 8 with `d^2 = r^2 + z^2 + b^2`): its
//!   singularities move from `r = +-i z` out to `+-i sqrt(z^2 + b^2)`, so its point samples on a
//!   lattice of spacing `h` sum to its integral up to roughly `e^(-2 pi b / h)` (Poisson
//!   summation), whatever `z_r` and the diffusion length are; the plane test measures at most
//!   6.7e-4 for `b = 1.5 h` (2.1e-4 for Richardson's form). Subtracting `beta p_z'` extrapolates it back to `beta = 0` along its
//!   tangent, so `R_far = R_d - O(b^4 / r^4) R_d` away from the footprint. The tangent costs one
//!   exponential per pole, the same as the point kernel `R_d(r) dA`: the gather pays nothing for
//!   the regularisation. (The same `O(b^4)` follows from Richardson's `2 R_b - R_{sqrt2 b}`, at
//!   twice the exponentials; this kernel has half its `b^4` term.)
//! - `p_z` is completely monotone in `D`, hence convex, so `p(D) >= p(D + beta) - beta p'(D + beta)`:
//!   `R_near >= 0` pointwise, and `R_far >= R_b > 0`.
//! - `E_near` follows from integrating `R_far` with the antiderivative `G_z` (`p_z = -2 G_z'`), so
//!   it is exact and closed-form. It is the Taylor remainder `integral_0^beta y G_z''(z^2 + y) dy`
//!   of the convex `G_z`, hence `>= 0`; when `b << z` the closed form cancels, and the remainder
//!   is integrated instead ([`taylor_remainder`]).
//! - `w` is the footprint: 1 inside, 0 outside, with a smoothstep edge of half-width
//!   `BUMP_DELTA rho` centred so that `integral w 2 pi r dr = dA` exactly. It ends at
//!   `1.244 rho`, short of any neighbour at the sample spacing (`>= 1.77 rho`), so each sample's
//!   near energy stays on its own footprint.
//!
//! Together: `integral K 2 pi r dr = dA R_d,total` exactly for every `dA`; at its own centre a
//! sample returns `K(0) = E_near + dA R_far(0)`, which tends to the disk integral
//! `P(rho) -> R_d,total` when the spacing is much larger than the diffusion length and to
//! `dA R_d(0)` when it is much smaller than `z_r`. Far from the sample `K` is the point kernel
//! `R_d(r) dA` to a relative `(15/8)(b/r)^4` (under 1e-3 beyond `6 b`), so the hierarchical
//! gather may stand a far cluster of samples in for its members with the same kernel.
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

/// The far part `R_far(r) = R_b(r) - b^2 dR_b/d(b^2)`: the regularised profile extrapolated to
/// `b = 0` along its tangent (see the module doc); `R_b(r) <= R_far(r) <= R_d(r)`. One
/// exponential per pole; every factor is a ratio `<= 1` or a bounded polynomial so nothing
/// overflows.
pub fn r_d_far(dipole: &Dipole, r: f64, b: f64) -> f64 {
    let beta = b * b;
    let s = dipole.sigma_tr;
    let pole = |z: f64| {
        let d = (r * r + z * z + beta).sqrt();
        let inv_d = 1.0 / d;
        let q = beta * inv_d * inv_d; // <= 1
        (z * inv_d) * inv_d * (-s * d).exp() * (s + inv_d + 0.5 * q * (s * s * d + 3.0 * s + 3.0 * inv_d))
    };
    dipole.alpha_prime / (4.0 * PI) * (pole(dipole.z_r) + pole(dipole.z_v))
}

/// The far kernel of a cluster of samples seen from `r` away from its centroid, per unit of its
/// power, to second order in its spread: `R_far(r) + (1/2) tr(H C)` with `C` the power-weighted
/// covariance of the members' positions about the centroid and `H` the Hessian of the profile
/// in the receiver's position (the first-order term vanishes about the centroid). Taking the
/// profile as a function of `D = r^2`, `H = 2 R' I + 4 R'' u u^T` (`u` the offset from the
/// centroid), so `(1/2) tr(H C) = R' tr C + 2 R'' r^2 (û^T C û)`; `tr_cov = tr C` and
/// `axial_cov = û^T C û`, the variance along the direction to the receiver, are passed in (both
/// in scene units squared, so nothing of order `r^4` is formed).
///
/// The derivatives are those of the regularised profile `R_b` (each pole
/// `z e^(-s d)(s d + 1)/d^3`, `d^2 = r^2 + z^2 + b^2`), so the correction shares the far kernel's
/// exponential; next to `R_d`'s they differ by `O(b^2/r^2)` of a term that is itself second order:
/// ```text
/// dp/dD   = -z e^(-s d) (s^2 d^2 + 3 s d + 3) / (2 d^5)
/// d2p/dD2 =  z e^(-s d) (s^3 d^3 + 6 s^2 d^2 + 15 s d + 15) / (4 d^7)
/// ```
/// With no spread it is [`r_d_far`]. The hierarchical gather evaluates it for every cluster it
/// uses whole (glsl/common/dipole.glsl's twin).
pub fn r_d_far_cluster(dipole: &Dipole, r: f64, b: f64, tr_cov: f64, axial_cov: f64) -> f64 {
    let beta = b * b;
    let s = dipole.sigma_tr;
    let pole = |z: f64| {
        let d = (r * r + z * z + beta).sqrt();
        let inv_d = 1.0 / d;
        let q = beta * inv_d * inv_d;
        let e = (-s * d).exp();
        let sd = s * d;
        let far = s + inv_d + 0.5 * q * (s * s * d + 3.0 * s + 3.0 * inv_d);
        // (1/2) tr(H C) over (z/d)(1/d^2) e^(-s d): u = tr C / d^2, v = r^2 (û^T C û) / d^4.
        let (u, v) = (tr_cov * inv_d * inv_d, axial_cov * inv_d * inv_d * (r * inv_d) * (r * inv_d));
        let spread = 0.5 * (-(sd * sd + 3.0 * sd + 3.0) * u + (sd * sd * sd + 6.0 * sd * sd + 15.0 * sd + 15.0) * v);
        (z * inv_d) * inv_d * e * (far + spread * inv_d)
    };
    dipole.alpha_prime / (4.0 * PI) * (pole(dipole.z_r) + pole(dipole.z_v))
}

/// The near energy `E_near(b) = R_d,total - integral R_far 2 pi r dr >= 0`, in closed form (see
/// the module doc), evaluated without cancellation.
pub fn near_energy(dipole: &Dipole, b: f64) -> f64 {
    let beta = b * b;
    0.5 * dipole.alpha_prime
        * (taylor_remainder(dipole.z_r, dipole.sigma_tr, beta) + taylor_remainder(dipole.z_v, dipole.sigma_tr, beta))
}

/// `G(z^2) - G(z^2 + beta) + beta G'(z^2 + beta)` with `G(D) = z e^(-s sqrt(D)) / sqrt(D)`: the
/// remainder of the tangent of `G` at `z^2 + beta`, extrapolated to `z^2`, which is
/// `integral_0^beta y G''(z^2 + y) dy >= 0`.
///
/// When the two points are close (`(d1 - z)/z <= 0.1` and `s (d1 - z) <= 0.5`, `d1 = sqrt(z^2 + beta)`)
/// the closed form cancels, so the integral is taken instead, by 5-point Gauss-Legendre (the
/// integrand is smooth there; error below 1e-9), with
/// `G''(D) = z e^(-s q) (s^2 q^2 + 3 s q + 3) / (4 q^5)`, `q = sqrt(D)`, each factor formed as a
/// ratio `<= 1` so nothing overflows in f32. Otherwise the closed form
/// `e^(-s z) [1 - (z/d1) e^(-s (d1 - z)) (1 + (beta/2 d1^2)(s d1 + 1))]` loses at most a digit.
pub fn taylor_remainder(z: f64, s: f64, beta: f64) -> f64 {
    let d1 = (z * z + beta).sqrt();
    let gap = beta / (z + d1); // d1 - z without cancellation
    if gap <= REMAINDER_MAX_SPREAD * z && s * gap <= REMAINDER_MAX_DECAY {
        const X: [f64; 5] =
            [-0.906_179_845_938_664, -0.538_469_310_105_683, 0.0, 0.538_469_310_105_683, 0.906_179_845_938_664];
        const W: [f64; 5] = [
            0.236_926_885_056_189,
            0.478_628_670_499_366,
            0.568_888_888_888_889,
            0.478_628_670_499_366,
            0.236_926_885_056_189,
        ];
        // (beta/2) y G''(z^2 + y) = (y/q^2)(beta/q^2)(z/q) e^(-s q)(s^2 q^2 + 3 s q + 3)/8
        let mut sum = 0.0;
        for k in 0..5 {
            let y = 0.5 * beta * (1.0 + X[k]);
            let q_sq = z * z + y;
            let q = q_sq.sqrt();
            let sq = s * q;
            sum += W[k] * (y / q_sq) * (beta / q_sq) * (z / q) * (-sq).exp() * (sq * sq + 3.0 * sq + 3.0);
        }
        0.125 * sum
    } else {
        let q = beta / (d1 * d1);
        (-s * z).exp() * (1.0 - (z / d1) * (-s * gap).exp() * (1.0 + 0.5 * q * (s * d1 + 1.0)))
    }
}

/// `integral over r > R of R_near(r) 2 pi r dr`: the near energy lying farther than `R` from
/// its receiver, `R_near = R_d - R_far` with `b^2 = beta`. With `q0 = sqrt(R^2 + z^2)`, each
/// pole's tail is the Taylor remainder of `G_z` at `q0^2` instead of `z^2` (the module doc's
/// `E_near`, integrated from `R` rather than 0), and `G_z = (z / q0) G_q0`, so
/// `(alpha'/2) sum_z (z / q0) taylor_remainder(q0, sigma_tr, beta)`; at `R = 0` it is `E_near`.
pub fn near_tail(dipole: &Dipole, beta: f64, radius: f64) -> f64 {
    let s = dipole.sigma_tr;
    let pole = |z: f64| {
        let q0 = (radius * radius + z * z).sqrt();
        (z / q0) * taylor_remainder(q0, s, beta)
    };
    0.5 * dipole.alpha_prime * (pole(dipole.z_r) + pole(dipole.z_v))
}

/// The second moment of the near part about its receiver, `integral r^2 R_near(r) 2 pi r dr /
/// E_near` (scene units squared, `b^2 = beta`), from its tail: integrating by parts,
/// `integral r^2 R_near 2 pi r dr = integral_0^inf 2 R near_tail(R) dR`. Taken in `u = ln R`
/// (`2 R^2 near_tail(R) du`), in panels of half a unit, 4-point Gauss-Legendre each, from
/// `1e-4 l` to `1e4 l` with `l = sqrt(z_v^2 + b^2)`, `R_near`'s width: below, the integrand is
/// at most `2 R E_near`; above, `R_near` is `R_d` times `O(b^4 / r^4)`; either side holds under
/// `1e-8` of the whole (`tests/optics.rs` checks it against a direct integral to 1e-3). Zero when
/// there is no near energy.
pub fn near_second_moment(dipole: &Dipole, beta: f64) -> f64 {
    let total = near_tail(dipole, beta, 0.0);
    if total <= 0.0 || beta <= 0.0 {
        return 0.0;
    }
    let ell = (dipole.z_v * dipole.z_v + beta).sqrt();
    let (u0, u1) = ((1e-4 * ell).ln(), (1e4 * ell).ln());
    let panels = ((u1 - u0) / 0.5).ceil();
    let h = (u1 - u0) / panels;
    let mut sum = 0.0;
    for p in 0..panels as usize {
        let centre = u0 + (p as f64 + 0.5) * h;
        for k in 0..2 {
            for sign in [-1.0, 1.0] {
                let r = (centre + sign * 0.5 * h * GL4_X[k]).exp();
                sum += GL4_W[k] * 2.0 * r * r * near_tail(dipole, beta, r);
            }
        }
    }
    0.5 * h * sum / total
}

/// Gauss-Legendre nodes (positive half) and weights, 4 points on `[-1, 1]`.
const GL4_X: [f64; 2] = [0.339_981_043_584_856, 0.861_136_311_594_053];
const GL4_W: [f64; 2] = [0.652_145_154_862_546, 0.347_854_845_137_454];

/// The fraction of a receiver's near energy `E_near(b)` that stays on the surface when an open
/// boundary (taken as a straight edge) passes `t` from it: `1 - missing / E_near` with
///
/// ```text
/// missing = integral over the half-plane beyond the edge of R_near dA
///         = (1 / 2 pi) integral_{-pi/2}^{pi/2} T(t / cos theta) d theta     (T = near_tail)
///         = (1 / pi) integral_0^inf T(t cosh v) / cosh v dv
/// ```
///
/// (polar coordinates about the receiver: the ray at angle `theta` from the edge's normal leaves
/// the surface at `t / cos theta`; then `t / cos theta = t cosh v`, which spreads the sharp
/// turn the first form has near `theta = pi/2` when `t` is small next to `T`'s width over about
/// one unit of `v`). `1/2` on the edge, rising to 1 within a few `l = sqrt(z_v^2 + b^2)`, the
/// width of `R_near`; 1 from [`NEAR_EDGE_REACH`]` l` on.
///
/// Why: the near-field blend assumes a whole plane around every receiver (the module doc's
/// `E_near`), so without this factor a receiver on an open boundary keeps the near energy that
/// should have left through it: the rim of an open mesh reads up to twice the exact half-plane
/// integral, and a corner four times (the study's defect 3, docs/STUDY.md). The gathers multiply
/// the blended near exitance by this factor for each of the two nearest boundary directions
/// (`mesh::boundary`), which is exact at a right-angled corner for a separable kernel and close
/// for this one.
///
/// The `v` integral runs to `acosh(NEAR_EDGE_REACH l / t)` in panels of at most one unit, 4-point
/// Gauss-Legendre each (tests/optics.rs checks it against a direct quadrature of the half-plane).
pub fn near_kept_at_edge(dipole: &Dipole, b: f64, t: f64) -> f64 {
    let beta = b * b;
    let ell = (dipole.z_v * dipole.z_v + beta).sqrt();
    if t.is_nan() || t >= NEAR_EDGE_REACH * ell || b <= 0.0 {
        return 1.0;
    }
    let total = near_tail(dipole, beta, 0.0);
    if total <= 0.0 {
        return 1.0;
    }
    if t <= NEAR_EDGE_TOUCH * ell {
        return 0.5;
    }
    let v_max = (NEAR_EDGE_REACH * ell / t).acosh();
    let panels = v_max.ceil().clamp(1.0, NEAR_EDGE_PANELS);
    let h = v_max / panels;
    let mut sum = 0.0;
    for p in 0..panels as usize {
        let centre = (p as f64 + 0.5) * h;
        for k in 0..2 {
            for sign in [-1.0, 1.0] {
                let v = centre + sign * 0.5 * h * GL4_X[k];
                sum += GL4_W[k] * near_tail(dipole, beta, t * v.cosh()) / v.cosh();
            }
        }
    }
    let missing = 0.5 * h * sum / PI;
    (1.0 - missing / total).clamp(0.0, 1.0)
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
    let b = B_PER_SQRT_AREA * area.sqrt();
    let rho = (area / PI).sqrt();
    far_kernel(dipole, r, area) + near_energy(dipole, b) * footprint_weight(r / rho)
}

/// The far part of [`footprint_kernel`] alone, `dA R_far(r)` with `b = 1.5 sqrt(dA)`, without
/// the footprint's near energy.
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
    area * r_d_far(dipole, r, B_PER_SQRT_AREA * area.sqrt())
}

/// Shepard weight of a sample in the near-field blend at distance `r`: `(1 - (r/R)^2)^3` inside
/// `R = k sqrt(dA)`, 0 outside; smooth (C2) at the rim. `k` is the channel's factor from
/// [`near_blend_radii`] (the sparse gather's is [`NEAR_BLEND_RADIUS`]).
pub fn near_blend_weight(r: f64, area: f64, k: f64) -> f64 {
    let radius = k * area.max(0.0).sqrt();
    if r.is_nan() || r >= radius {
        return 0.0;
    }
    let t = 1.0 - (r / radius) * (r / radius);
    t * t * t
}

/// Per channel, the radius factor `k` of the near-field blend (`R = k sqrt(dA)`,
/// [`near_blend_weight`]) for samples of mean area `mean_area`: the one whose blend smooths the
/// near exitance as much as the exact near part does,
///
/// ```text
/// k^2 dA / 5 = m2 = integral r^2 R_near(r) 2 pi r dr / E_near      ([`near_second_moment`]),
/// ```
///
/// clamped to [`NEAR_BLEND_RADIUS`], [`NEAR_BLEND_RADIUS_MAX`].
///
/// Why: the exact near part `integral R_near(|x - y|) E_t(y) dA(y)` is `E_near` times `E_t`
/// smoothed by `R_near`, which to second order is `E_t(x) + (m2 / 4) lap E_t(x)`; the blend
/// smooths with its own weights instead, whose second moment in the plane is `R^2 / 5`
/// (`integral (1 - u)^3 u du / integral (1 - u)^3 du` with `u = r^2 / R^2`). With one radius for
/// every channel the two differ, and the vertex gather read low wherever `E_t` bends up (up to
/// 1.8% of the exitance beside the terminator) and high where it bends down: the study's
/// defect 2 (docs/STUDY.md). `R_near`'s width is `sqrt(z_v^2 + b^2)`, so it differs by channel.
/// The floor keeps neighbours overlapping where `R_near` is narrower than the spacing (there the
/// planner computes the channel locally instead, `render::plan`).
pub fn near_blend_radii(dipoles: &[Dipole; 3], mean_area: f64) -> [f64; 3] {
    if mean_area.is_nan() || mean_area <= 0.0 {
        return [NEAR_BLEND_RADIUS; 3];
    }
    let beta = B_PER_SQRT_AREA * B_PER_SQRT_AREA * mean_area;
    dipoles.each_ref().map(|d| {
        let k = (5.0 * near_second_moment(d, beta) / mean_area).sqrt();
        if k.is_nan() { NEAR_BLEND_RADIUS } else { k.clamp(NEAR_BLEND_RADIUS, NEAR_BLEND_RADIUS_MAX) }
    })
}

/// Whether a cluster of samples of total area `area`, all at least `dist` away from a receiver,
/// adds at most [`TREE_PRUNE_FRACTION`] of `R_d,total` to its exitance under uniform light in
/// every channel: `area R_d(dist) <= TREE_PRUNE_FRACTION R_d,total`, which bounds the cluster's far
/// sum because `R_far <= R_d` and `R_d` falls with distance (callers ensure no sample's near
/// blend reaches the receiver).
pub fn negligible_cluster(dipoles: &[Dipole; 3], area: f64, dist: f64) -> bool {
    dipoles.iter().all(|d| area * d.r_d(dist) <= TREE_PRUNE_FRACTION * d.r_d_total())
}

/// `3t^2 - 2t^3` on `[0, 1]`, clamped: a blend weight with zero slope at both ends.
pub fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

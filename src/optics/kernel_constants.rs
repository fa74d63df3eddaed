// The near-field kernel's constants, written once for both twins: `optics::kernel` defines them
// as `pub const NAME: f64`, and build.rs writes them as `const float DIPOLE_NAME` into the
// generated header `kernel_constants.glsl`, which glsl/common/dipole.glsl includes.
kernel_constants! {
    /// Regularization length `b` in units of `sqrt(dA)`: the lattice-sum error of the far part
    /// falls as `e^(-2 pi b / h)` (at most 6.7e-4 here, measured by tests/optics.rs), while larger `b` puts
    /// more light into the footprint.
    B_PER_SQRT_AREA = 1.5;
    /// Half-width of the footprint's smooth edge, in units of `rho`.
    BUMP_DELTA = 0.25;
    /// [`taylor_remainder`] integrates the second derivative when `(d1 - z) / z` is at most this...
    REMAINDER_MAX_SPREAD = 0.1;
    /// ... and `sigma_tr (d1 - z)` is at most this; otherwise the closed form cancels little.
    REMAINDER_MAX_DECAY = 0.5;
    /// The least radius of a sample's near-field blend weight, in units of `sqrt(dA)`, and the
    /// sparse gather's radius: wide enough that neighbours overlap (spacing is about `sqrt(dA)`),
    /// so the blend is a partition of unity with no gaps even for irregular sample sets.
    /// [`near_blend_radii`] widens it per channel to match `R_near`'s second moment.
    NEAR_BLEND_RADIUS = 1.5;
    /// The greatest near-blend radius, in units of `sqrt(dA)`. A channel whose `R_near` is wider
    /// (its `z_v` large next to the spacing) has little near energy, so matching it further buys
    /// little: on the ketchup sphere at 6,400 samples, a cap of 3 left green at 0.58% RMS, 4 at
    /// 0.25%, none at 0.25% (red wanted 16, and read the same at every cap); a wider radius
    /// costs the hierarchical gather `k^2` more samples summed one by one near each receiver.
    NEAR_BLEND_RADIUS_MAX = 4.0;
    /// The hierarchical gather drops a cluster of samples (with its subtree) when, under uniform
    /// light, it could add at most this fraction of `R_d,total` in every channel
    /// ([`negligible_cluster`]).
    TREE_PRUNE_FRACTION = 1e-6;
    /// Beyond this many `l = sqrt(z_v^2 + b^2)` (the width of the near part `R_near`) from an
    /// open boundary a receiver keeps all its near energy ([`near_kept_at_edge`] is 1): what lies
    /// beyond is under 1e-4 of `E_near` (tests/optics.rs).
    NEAR_EDGE_REACH = 6.0;
    /// Within this many `l` of an open boundary a receiver is on it and keeps half.
    NEAR_EDGE_TOUCH = 1e-6;
    /// At most this many panels of the edge factor's angular integral (one per unit of `v`,
    /// which runs to `acosh(NEAR_EDGE_REACH / NEAR_EDGE_TOUCH)`, about 16.3).
    NEAR_EDGE_PANELS = 17.0;
}

//! The seed paper's geometric feature sampling (Xu, Song and Fu, section 3, Algorithm 1 and
//! Eq. 12), made robust, followed by Turk repulsion whose density follows curvature.
//!
//! # How the paper is read here
//!
//! The paper begins with random points, then adds points at curvature-weighted centres of the
//! triangles that rank high on curvature and on area (Eq. 12:
//! `newCoord = sum_i Curvature[i] * Coord[i] / sum_i Curvature[i]` over the three corners). Algorithm 1
//! takes the n triangles with the largest curvature and the n with the largest area, 2n new
//! points in all. It leaves open which curvature, how n relates to the budget, and what happens
//! when the weights cancel. The exact procedure implemented:
//!
//! 1. `Curvature[i]` is |H_i|, the magnitude of the mean curvature at vertex i (cotangent
//!    Laplace-Beltrami, Meyer et al. 2003). A triangle's curvature is the mean of its three
//!    corners' |H|; its area is its own area.
//! 2. The budget is N in total: n = floor(N * feature_fraction / 2), at most half the triangle
//!    count, so 2n feature points plus N - 2n uniform random points make exactly N.
//! 3. The n triangles of largest curvature are taken first, then the n of largest area among
//!    those not yet taken, so the 2n points lie in 2n distinct triangles (a triangle that ranks
//!    high on both lists would otherwise get two coincident points). Ties go to the lower index.
//! 4. In each chosen triangle the new point has barycentric weights w_i = |H_i| / sum_j |H_j|
//!    (Eq. 12 with |curvature|, so no weight is negative and the point is a convex combination
//!    of the corners, never outside the triangle). When sum_j |H_j| is zero, or negligible next
//!    to the mesh's mean |H|, the point is the plain centroid. The weights are blended with 5%
//!    of the centroid so that two triangles dominated by the same sharp corner do not both put
//!    their point exactly on that vertex.
//! 5. The N points are then relaxed by Turk's repulsion (Turk 1992) with a radius that follows
//!    a curvature density rho = 1 + min(c |H|_s / mean |H|_s, cap) (|H|_s: |H| averaged over
//!    one-rings twice, so that scan noise does not drive the density; mean by area), r_i =
//!    2 sqrt(integral(rho) / (N rho_i)), which reduces to Turk's 2 sqrt(A / N) where rho is
//!    constant. Regions of high |H| therefore end up with up to (1 + cap) times more points
//!    per unit area than flat ones.
//!
//! Defaults ([`FeatureParams::default`]): feature_fraction 0.5 (so 2n = 2 floor(N / 4)), c = 1,
//! cap = 3, 80 repulsion iterations with step 0.1.

use super::turk::{Radius, TurkParams, relax};
use super::walk::SurfacePoint;
use crate::mesh::Mesh;

/// Settings of the feature sampler.
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureParams {
    /// Fraction of the budget N placed by Algorithm 1 (the 2n feature points); the rest start
    /// uniformly at random.
    pub feature_fraction: f64,
    /// Strength c of the curvature density: rho = 1 + min(c |H| / mean |H|, cap).
    pub contrast: f64,
    /// Cap on the density excess, so the flattest and the most curved regions differ by at most
    /// a factor (1 + cap) in points per unit area.
    pub cap: f64,
    /// The repulsion after placement.
    pub turk: TurkParams,
}

impl Default for FeatureParams {
    fn default() -> Self {
        // Twice Turk's default iterations: Algorithm 1 starts half the points in a few tight
        // clusters, further from equilibrium than a random start.
        FeatureParams {
            feature_fraction: 0.5,
            contrast: 1.0,
            cap: 3.0,
            turk: TurkParams { iterations: 80, ..TurkParams::default() },
        }
    }
}

/// Share of the plain centroid mixed into the Eq. 12 weights (see step 4 above).
const CENTROID_BLEND: f64 = 0.05;

/// Below this fraction of the mesh's mean |H|, a triangle's curvature weights count as zero.
const NEGLIGIBLE: f64 = 1e-9;

/// Per-vertex |H| averaged twice over one-rings (mixed-area weighted, the vertex included).
pub fn smoothed_abs_mean_curvature(mesh: &Mesh, passes: usize) -> Vec<f64> {
    let area = mesh.mixed_areas();
    let mut cur: Vec<f64> = mesh.mean_curvature().iter().map(|h| h.abs()).collect();
    let mut next = vec![0.0; cur.len()];
    for _ in 0..passes {
        for (v, out) in next.iter_mut().enumerate() {
            let (mut w, mut s) = (area[v], area[v] * cur[v]);
            for &j in mesh.vertex_neighbours(v) {
                w += area[j as usize];
                s += area[j as usize] * cur[j as usize];
            }
            *out = if w > 0.0 { s / w } else { cur[v] };
        }
        std::mem::swap(&mut cur, &mut next);
    }
    cur
}

/// The per-vertex density rho = 1 + min(contrast |H|_s / mean |H|_s, cap) of step 5.
pub fn curvature_density(mesh: &Mesh, contrast: f64, cap: f64) -> Vec<f64> {
    let h = smoothed_abs_mean_curvature(mesh, 2);
    let area = mesh.mixed_areas();
    let total: f64 = area.iter().sum();
    let mean = h.iter().zip(area).map(|(h, a)| h * a).sum::<f64>() / total;
    if mean.is_nan() || mean <= 0.0 || !mean.is_finite() {
        return vec![1.0; h.len()];
    }
    h.iter().map(|&x| 1.0 + (contrast * x / mean).min(cap)).collect()
}

/// How many feature points (2n) Algorithm 1 places for a budget of `count`.
pub fn feature_point_count(mesh: &Mesh, count: usize, feature_fraction: f64) -> usize {
    let n = ((count as f64 * feature_fraction.clamp(0.0, 1.0)) / 2.0).floor() as usize;
    2 * n.min(mesh.triangles().len() / 2)
}

/// Algorithm 1 with Eq. 12 as read in the module documentation (steps 1 to 4): `2n` points in
/// `2n` distinct triangles, the curvature ones first.
pub fn feature_points(mesh: &Mesh, two_n: usize) -> Vec<SurfacePoint> {
    let n = two_n / 2;
    let tris = mesh.triangles();
    if n == 0 {
        return Vec::new();
    }
    assert!(2 * n <= tris.len(), "Algorithm 1 needs 2n = {} distinct triangles, the mesh has {}", 2 * n, tris.len());
    let abs_h: Vec<f64> = mesh.mean_curvature().iter().map(|h| h.abs()).collect();
    let tri_curv: Vec<f64> = tris.iter().map(|t| t.iter().map(|&v| abs_h[v as usize]).sum::<f64>() / 3.0).collect();
    let areas = mesh.triangle_areas();
    let mean_h = abs_h.iter().zip(mesh.mixed_areas()).map(|(h, a)| h * a).sum::<f64>() / mesh.total_area();

    let by_curvature = top_n(&tri_curv, n, &[]);
    let mut taken = vec![false; tris.len()];
    for &t in &by_curvature {
        taken[t as usize] = true;
    }
    let by_area = top_n(areas, n, &taken);

    by_curvature
        .iter()
        .chain(&by_area)
        .map(|&t| {
            let w = tris[t as usize].map(|v| abs_h[v as usize]);
            let sum = w[0] + w[1] + w[2];
            let eq12 = if sum.is_finite() && sum > NEGLIGIBLE * mean_h && sum > 0.0 {
                w.map(|x| x / sum)
            } else {
                [1.0 / 3.0; 3]
            };
            let bary = eq12.map(|x| (1.0 - CENTROID_BLEND) * x + CENTROID_BLEND / 3.0);
            SurfacePoint { triangle: t, bary }
        })
        .collect()
}

/// Indices of the `n` largest values not in `exclude` (empty for none), largest first, ties to
/// the lower index.
fn top_n(values: &[f64], n: usize, exclude: &[bool]) -> Vec<u32> {
    let mut idx: Vec<u32> = (0..values.len() as u32).filter(|&i| exclude.get(i as usize) != Some(&true)).collect();
    let order = |a: &u32, b: &u32| values[*b as usize].total_cmp(&values[*a as usize]).then(a.cmp(b));
    let n = n.min(idx.len());
    if n < idx.len() {
        idx.select_nth_unstable_by(n, order);
        idx.truncate(n);
    }
    idx.sort_unstable_by(order);
    idx
}

/// Step 5: repulsion with the curvature density, in place.
pub fn relax_by_curvature(mesh: &Mesh, points: &mut [SurfacePoint], params: &FeatureParams) {
    let density = curvature_density(mesh, params.contrast, params.cap);
    let integral: f64 = mesh
        .triangles()
        .iter()
        .zip(mesh.triangle_areas())
        .map(|(t, a)| a * t.iter().map(|&v| density[v as usize]).sum::<f64>() / 3.0)
        .sum();
    let base = 2.0 * (integral / points.len().max(1) as f64).sqrt();
    relax(mesh, points, Radius::Density { base, vertex_density: &density }, &params.turk);
}

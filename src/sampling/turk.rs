//! Point repulsion after Greg Turk, "Re-Tiling Polygonal Surfaces" (SIGGRAPH 1992), section 3:
//! every point is pushed away by the neighbours closer than a repulsion radius r with a force
//! growing as (r - d), moves in the plane of its triangle, and crosses edges onto neighbouring
//! triangles; a spatial hash finds the neighbours. Turk's uniform radius is r = 2 sqrt(A / n).
//!
//! For density that varies over the surface (Turk's own curvature-adaptive variant, and the
//! `feature` sampler here), each point carries its own radius r_i proportional to
//! 1 / sqrt(density) and a pair uses the mean of the two radii, so forces stay symmetric.

use glam::DVec3;
use rayon::prelude::*;

use super::hash::SpatialHash;
use super::walk::{SurfacePoint, walk};
use crate::mesh::Mesh;

/// Settings of the repulsion.
#[derive(Clone, Debug, PartialEq)]
pub struct TurkParams {
    /// Number of repulsion iterations (Turk used a fixed count of some tens).
    pub iterations: usize,
    /// Fraction of the net force (a length) a point moves per iteration. Every point moves at once
    /// from the previous positions (a Jacobi step, so results do not depend on thread count);
    /// with about a dozen neighbours per point, values much above 0.15 oscillate.
    pub step: f64,
}

impl Default for TurkParams {
    fn default() -> Self {
        TurkParams { iterations: 40, step: 0.1 }
    }
}

/// The repulsion radius over the surface.
#[derive(Clone, Copy, Debug)]
pub enum Radius<'a> {
    /// The same radius everywhere.
    Uniform(f64),
    /// `base / sqrt(density)`, with `density` given per vertex and interpolated.
    Density {
        /// The radius where the density is 1.
        base: f64,
        /// Density per mesh vertex, interpolated over each triangle.
        vertex_density: &'a [f64],
    },
}

impl Radius<'_> {
    #[inline]
    fn at(&self, mesh: &Mesh, p: &SurfacePoint) -> f64 {
        match *self {
            Radius::Uniform(r) => r,
            Radius::Density { base, vertex_density } => {
                base / mesh.interpolate(vertex_density, p.triangle as usize, p.bary).max(1e-12).sqrt()
            }
        }
    }
}

/// Turk's radius for `n` points spread evenly over `area`.
pub fn turk_radius(area: f64, n: usize) -> f64 {
    2.0 * (area / n as f64).sqrt()
}

/// Run the repulsion on `points` in place.
///
/// The points are relaxed in Morton order, so that a point's neighbours lie near it in memory
/// (a random start scatters them, and fetching them was most of the time); everything that
/// depends on the order (the order neighbours' forces are summed in, the tie-break of coincident
/// points) follows the caller's order, so the result is bit for bit the same.
pub fn relax(mesh: &Mesh, points: &mut [SurfacePoint], radius: Radius<'_>, params: &TurkParams) {
    if points.len() < 2 || params.iterations == 0 {
        return;
    }
    let key = super::morton_key(mesh);
    // `rank[k]`: the caller's index of the k-th point in Morton order.
    let mut rank: Vec<u32> = (0..points.len() as u32).collect();
    rank.sort_by_cached_key(|&i| key(&points[i as usize]));
    let mut work: Vec<SurfacePoint> = rank.iter().map(|&i| points[i as usize]).collect();
    relax_ranked(mesh, &mut work, &rank, radius, params);
    for (p, &i) in work.into_iter().zip(&rank) {
        points[i as usize] = p;
    }
}

/// The repulsion on `points`, point `k` standing `rank[k]`-th in the order whose result it
/// reproduces.
fn relax_ranked(mesh: &Mesh, points: &mut Vec<SurfacePoint>, rank: &[u32], radius: Radius<'_>, params: &TurkParams) {
    // The hash lists each bucket's points in rank order: `fill[r]` is the point ranked r.
    let mut fill = vec![0u32; rank.len()];
    for (k, &r) in rank.iter().enumerate() {
        fill[r as usize] = k as u32;
    }
    let normals = mesh.face_normals();
    let mut positions = Vec::with_capacity(points.len());
    // Each point's face normal, read per neighbour: one array instead of two lookups apart.
    let mut facing: Vec<DVec3> = Vec::with_capacity(points.len());
    let mut radii = Vec::with_capacity(points.len());
    let mut next = Vec::with_capacity(points.len());
    let mut hash = SpatialHash::default();

    for iteration in 0..params.iterations {
        points.par_iter().map(|p| p.position(mesh)).collect_into_vec(&mut positions);
        points.par_iter().map(|p| normals[p.triangle as usize].as_dvec3()).collect_into_vec(&mut facing);
        points.par_iter().map(|p| radius.at(mesh, p)).collect_into_vec(&mut radii);
        let r_max = radii.iter().copied().fold(0.0, f64::max);
        hash.rebuild_in_order(&positions, r_max, Some(&fill));
        // A slowly shrinking step lets early iterations travel and late ones settle.
        let step = params.step * (1.0 - 0.5 * iteration as f64 / params.iterations as f64);

        points
            .par_iter()
            .enumerate()
            .map(|(i, sp)| {
                let t = sp.triangle as usize;
                let n = facing[i];
                let p = positions[i];
                let ri = radii[i];
                let mut force = DVec3::ZERO;
                hash.for_each_within(p, r_max, |j, d2| {
                    let j = j as usize;
                    if j == i {
                        return;
                    }
                    let rij = 0.5 * (ri + radii[j]);
                    if d2 >= rij * rij {
                        return;
                    }
                    // Points on the far side of a thin sheet (an ear) face the other way and do
                    // not crowd this side, so they do not push.
                    if facing[j].dot(n) < 0.0 {
                        return;
                    }
                    let d = d2.sqrt();
                    // The neighbour is laid into this point's tangent plane at its distance d, so
                    // a neighbour around a bend pushes with the full (r - d), not the smaller
                    // in-plane part of its offset.
                    let offset = p - positions[j];
                    let in_plane = offset - offset.dot(n) * n;
                    let dir = if d > 1e-9 * rij && in_plane.length_squared() > 1e-18 * d2 {
                        in_plane.normalize()
                    } else {
                        // Coincident points: push apart along a fixed edge of the triangle, in
                        // opposite senses for the two, so they separate deterministically.
                        let [a, b, _] = mesh.corners(t);
                        let e = (b - a).normalize_or_zero();
                        if rank[i] < rank[j] { e } else { -e }
                    };
                    force += (rij - d) * dir;
                });
                let mut disp = step * force;
                // No single step longer than half a radius: keeps crowded starts from flinging
                // points across the model.
                let len = disp.length();
                if len > 0.5 * ri {
                    disp *= 0.5 * ri / len;
                }
                walk(mesh, *sp, disp)
            })
            .collect_into_vec(&mut next);
        std::mem::swap(points, &mut next);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn relaxing_in_morton_order_gives_the_callers_order_result_bit_for_bit() {
        let mesh = crate::mesh::shapes::sphere(0.01, 8).unwrap();
        let n = 600;
        let start = super::super::random::random_points(&mesh, n, &mut rand_pcg::Pcg64::seed_from_u64(3));
        let radius = Radius::Uniform(turk_radius(mesh.total_area(), n));
        let params = TurkParams { iterations: 12, ..TurkParams::default() };
        let mut permuted = start.clone();
        relax(&mesh, &mut permuted, radius, &params);
        // The caller's order itself, as before the points were permuted.
        let mut plain = start.clone();
        relax_ranked(&mesh, &mut plain, &(0..n as u32).collect::<Vec<_>>(), radius, &params);
        assert_ne!(plain, start, "the points must move");
        assert_eq!(permuted, plain);
    }
}

//! From `render.max_error` to each translucent object's sample count: the surface facts the
//! error model weighs (`sampling::density`), measured on the placed meshes.

use crate::mesh::bvh::Bvh;
use crate::mesh::{LodLevel, Mesh};
use crate::optics::Dipole;
use crate::sampling::density::{self, ChannelError, SurfaceFacts};
use glam::DVec3;
use rayon::prelude::*;

/// Most vertices at which occlusion is ray cast (spread evenly over the vertex order).
const OCCLUSION_VERTICES: usize = 512;
/// Directions per vertex, over the hemisphere about its normal.
const OCCLUSION_DIRECTIONS: usize = 64;

/// How an object's sample count was chosen, with the prediction behind it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Density {
    /// Samples placed.
    pub count: usize,
    /// `render.max_error` it was chosen for (`None`: the count was given, `sampling.count` or
    /// `--samples`).
    pub target: Option<f64>,
    /// The facts the model weighed.
    pub facts: SurfaceFacts,
    /// Per channel (R, G, B), the predicted error at the count placed.
    pub predicted: [ChannelError; 3],
}

impl Density {
    /// The same facts with `count` samples given rather than chosen (a study's configuration).
    pub fn given(&self, dipoles: &[Dipole; 3], count: usize) -> Density {
        let radii = dipoles.each_ref().map(|d| d.profile_radius());
        Density { count, target: None, facts: self.facts, predicted: density::predict(&self.facts, radii, count) }
    }

    /// The worst channel's predicted error (`sampling::density::worst`).
    pub fn worst(&self) -> f64 {
        density::worst(&self.predicted)
    }
}

impl std::fmt::Display for Density {
    /// `30686 samples for render.max_error 1%: predicted R 0.52%, G 0.74%, B 1% (spacing / radius
    /// 0.087, 0.12, 0.155; thin part 1.15, 0.78, 0.626; shadow edges 2.47; facets 1.2e-6, ...)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let pct = |x: f64| format!("{:.3}%", 100.0 * x);
        match self.target {
            Some(t) => write!(f, "{} samples for render.max_error {}", self.count, pct(t))?,
            None => write!(f, "{} samples given (sampling.count or --samples)", self.count)?,
        }
        let [r, g, b] = self.predicted.map(|c| pct(c.error));
        if self.target.is_some_and(|t| self.worst() > t) && self.count >= density::MAX_CHOSEN {
            // The count stopped at the most the target may choose: say so rather than let the
            // target read as met.
            write!(f, " (the most a target may choose: the target is not reached)")?;
        }
        let three = |v: [f64; 3]| format!("{:.3}, {:.3}, {:.3}", v[0], v[1], v[2]);
        write!(
            f,
            ": predicted R {r}, G {g}, B {b} (spacing / radius {}; thin part {}; shadow edges {:.3}; facets {})",
            three(self.predicted.map(|c| c.spacing_over_radius)),
            three(self.predicted.map(|c| c.thin_term)),
            self.predicted[0].shadow_term,
            self.predicted.map(|c| format!("{:.2e}", c.facet_term)).join(", ")
        )
    }
}

/// The surface facts of an object's `mesh` with its levels of detail `levels` (finest first),
/// with `occluders` the scene's shadow casters.
pub fn surface_facts(mesh: &Mesh, levels: &[LodLevel], occluders: &Bvh, ray_offset: f64) -> SurfaceFacts {
    let (h, a) = (mesh.mean_curvature(), mesh.mixed_areas());
    let area: f64 = a.iter().sum();
    let h2 = h.iter().zip(a).map(|(h, a)| h * h * a).sum::<f64>() / area.max(f64::MIN_POSITIVE);
    let curvature_radius = if h2 > 0.0 { 1.0 / h2.sqrt() } else { f64::INFINITY };
    SurfaceFacts {
        area: mesh.total_area(),
        curvature_radius,
        occlusion: occlusion(mesh, occluders, ray_offset),
        // Level 0 is the whole mesh.
        edge_length: levels.first().map_or(0.0, |l| l.mean_edge),
    }
}

/// The area-weighted share of the hemisphere above `mesh` that `occluders` block, ray cast at
/// up to [`OCCLUSION_VERTICES`] vertices ([`receiver_subset`]) in [`OCCLUSION_DIRECTIONS`] fixed
/// directions each (a spherical Fibonacci set, so the answer is the same on every run).
fn occlusion(mesh: &Mesh, occluders: &Bvh, eps: f64) -> f64 {
    let picks = receiver_subset(mesh.positions().len(), Some(OCCLUSION_VERTICES));
    let directions = fibonacci_sphere(2 * OCCLUSION_DIRECTIONS);
    let (blocked, weight) = picks
        .par_iter()
        .map(|&v| {
            let p = mesh.positions()[v].as_dvec3();
            let n = mesh.vertex_normals()[v].as_dvec3();
            let (mut hits, mut seen) = (0usize, 0usize);
            for d in directions.iter().filter(|d| d.dot(n) > 0.0) {
                seen += 1;
                if occluders.occluded(p + n * eps, *d, eps, f64::INFINITY) {
                    hits += 1;
                }
            }
            let share = if seen > 0 { hits as f64 / seen as f64 } else { 0.0 };
            let area = mesh.mixed_areas()[v];
            (share * area, area)
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    if weight > 0.0 { blocked / weight } else { 0.0 }
}

/// `n` unit directions spread evenly over the sphere (spherical Fibonacci lattice).
fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5.0f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / n as f64;
            let ring = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            DVec3::new(ring * phi.cos(), ring * phi.sin(), z)
        })
        .collect()
}

/// The sample count for a translucent object of `dipoles` and the prediction behind it:
/// `given` (`sampling.count`) when set, else the fewest samples `sampling::density::count_for`
/// finds for `max_error`.
pub fn choose_count(
    dipoles: &[Dipole; 3],
    facts: SurfaceFacts,
    given: Option<usize>,
    max_error: f64,
) -> (usize, Density) {
    let radii = dipoles.each_ref().map(|d| d.profile_radius());
    let count = given.unwrap_or_else(|| density::count_for(&facts, radii, max_error));
    let predicted = density::predict(&facts, radii, count);
    (count, Density { count, target: given.is_none().then_some(max_error), facts, predicted })
}

/// The vertices of a mesh of `count` vertices picked for work done at some of them: all of
/// them, or `max` spread evenly over the vertex order (vertex `floor((i + 1/2) count / max)` for
/// `i < max`), so the subset is the same on every run. Where occlusion is ray cast here, and
/// where the truth is computed on a subset (`reference::truth`).
pub fn receiver_subset(count: usize, max: Option<usize>) -> Vec<usize> {
    match max {
        Some(m) if m < count => (0..m).map(|i| ((2 * i + 1) * count) / (2 * m)).collect(),
        _ => (0..count).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The count a target chooses on a bunny-sized surface, with its prediction.
    fn density(target: f64) -> Density {
        let facts = SurfaceFacts { area: 5e-3, curvature_radius: 5e-3, occlusion: 0.1, edge_length: 5e-4 };
        let radii = [5e-3, 3.7e-3, 2.8e-3];
        let count = density::count_for(&facts, radii, target);
        Density { count, target: Some(target), facts, predicted: density::predict(&facts, radii, count) }
    }

    #[test]
    fn a_count_stopped_at_its_limit_says_the_target_is_not_reached() {
        let capped = density(crate::scene::MIN_MAX_ERROR);
        assert_eq!(capped.count, density::MAX_CHOSEN, "this surface must need more than the cap");
        assert!(capped.worst() > crate::scene::MIN_MAX_ERROR);
        assert!(capped.to_string().contains("the target is not reached"), "{capped}");
        let met = density(0.01);
        assert!(met.worst() <= 0.01 && !met.to_string().contains("not reached"), "{met}");
    }
}

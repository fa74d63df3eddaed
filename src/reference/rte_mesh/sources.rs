//! Where photons start: the lights that reach the object, and the (light, triangle) pairs drawn
//! in proportion to the flux each brings.

use super::geometry::Geometry;
use crate::mesh::bvh::Bvh;
use crate::reference::light_incidence;
use crate::scene::lights::PreparedLight;

/// Where photons start: (light, triangle) pairs with the cumulative share of the flux.
pub(super) struct Sources {
    pub(super) pairs: Vec<(usize, usize)>,
    cdf: Vec<f64>,
    total: f64,
}

impl Sources {
    /// Each pair's weight: the triangle's area times the largest `E cos` (summed over channels)
    /// at its corners. It is zero only where the light cannot reach the face: for a plane
    /// triangle `cos` is affine in the point, so it is nowhere positive if at no corner. (A spot
    /// light's cone narrower than a triangle and between its corners is missed.)
    pub(super) fn new(geometry: &Geometry, lights: &[PreparedLight]) -> Sources {
        let (mut pairs, mut cdf, mut total) = (Vec::new(), Vec::new(), 0.0);
        for (l, light) in lights.iter().enumerate() {
            for (t, n) in geometry.normals.iter().enumerate() {
                let best = geometry
                    .mesh
                    .corners(t)
                    .iter()
                    .map(|p| {
                        let (wi, e, _) = light_incidence(light, *p);
                        n.dot(wi).max(0.0) * e.element_sum()
                    })
                    .fold(0.0, f64::max);
                let weight = best * geometry.mesh.triangle_areas()[t];
                if weight > 0.0 {
                    total += weight;
                    pairs.push((l, t));
                    cdf.push(total);
                }
            }
        }
        Sources { pairs, cdf, total }
    }

    /// The pair at `u` in [0, 1) and its probability.
    pub(super) fn pick(&self, u: f64) -> ((usize, usize), f64) {
        let x = u * self.total;
        let k = self.cdf.partition_point(|&c| c <= x).min(self.pairs.len() - 1);
        let below = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        (self.pairs[k], (self.cdf[k] - below) / self.total)
    }
}

/// What a scene's lights and shadow casters are to one object.
pub(super) struct Lighting<'a> {
    pub(super) lights: &'a [PreparedLight],
    pub(super) occluders: &'a Bvh,
    /// Visibility rays start this far off the surface.
    pub(super) eps: f64,
}

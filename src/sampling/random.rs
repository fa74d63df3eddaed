//! Uniform random points by area: a triangle chosen with probability proportional to its area
//! (binary search in the cumulative areas), then a uniform point in it by the square-root warp
//! (Osada et al. 2002, "Shape distributions", Eq. 1).

use rand::RngExt;
use rand_pcg::Pcg64;

use super::walk::SurfacePoint;
use crate::mesh::Mesh;

pub(crate) struct AreaTable {
    cumulative: Vec<f64>,
}

impl AreaTable {
    pub fn new(mesh: &Mesh) -> AreaTable {
        let mut acc = 0.0;
        let cumulative = mesh
            .triangle_areas()
            .iter()
            .map(|a| {
                acc += a;
                acc
            })
            .collect();
        AreaTable { cumulative }
    }

    pub fn sample(&self, rng: &mut Pcg64) -> SurfacePoint {
        let total = *self.cumulative.last().expect("a mesh has at least one triangle");
        let x = rng.random::<f64>() * total;
        let t = self.cumulative.partition_point(|&c| c <= x).min(self.cumulative.len() - 1);
        let s = rng.random::<f64>().sqrt();
        let v = rng.random::<f64>();
        SurfacePoint { triangle: t as u32, bary: [1.0 - s, s * (1.0 - v), s * v] }
    }
}

/// `n` independent uniform points on the surface.
pub fn random_points(mesh: &Mesh, n: usize, rng: &mut Pcg64) -> Vec<SurfacePoint> {
    let table = AreaTable::new(mesh);
    (0..n).map(|_| table.sample(rng)).collect()
}

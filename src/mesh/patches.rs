//! Patches of a mesh's surface: a partition of its vertices into regions of about equal area,
//! by k-means (Lloyd 1982) on the position and the normal, the normal scaled by a patch's
//! radius so that the two sides of a thin part fall in different patches. The transport kernel
//! (`optics::transport`) is tabulated between them.

use super::Mesh;
use glam::DVec3;
use rayon::prelude::*;

/// Lloyd iterations after the farthest-point start.
const LLOYD: usize = 6;
/// Patches a point's value is blended from ([`Patches::neighbours`]).
pub const NEIGHBOURS: usize = 8;
/// The width of the blend between patches, in patch radii.
pub const BLEND: f64 = 1.0;

/// A point's features: its position, then its unit normal times the patches' radius.
pub type Features = [f64; 6];

/// A partition of a mesh's vertices into patches (see the module's documentation).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Patches {
    /// Each vertex's patch.
    pub of_vertex: Vec<u32>,
    /// Each patch's centre in the features' space.
    pub centres: Vec<Features>,
    /// Each patch's area: its vertices' dual cells.
    pub area: Vec<f64>,
    /// Each vertex's dual cell area: a third of each of its triangles.
    pub cells: Vec<f64>,
    /// The radius of a disc of a patch's mean area: the normal's scale in the features, and the
    /// width of the blend between patches.
    pub radius: f64,
}

/// Each vertex's barycentric dual cell area: a third of each of its triangles.
pub fn cell_areas(mesh: &Mesh) -> Vec<f64> {
    let mut cells = vec![0.0; mesh.positions().len()];
    for (t, tri) in mesh.triangles().iter().enumerate() {
        for &v in tri {
            cells[v as usize] += mesh.triangle_areas()[t] / 3.0;
        }
    }
    cells
}

/// Each vertex's dual cell's centroid: in a triangle `(a, b, c)` the cell of `a` (the
/// quadrilateral of `a`, the two edges' midpoints and the centroid) has its centroid at
/// `(22 a + 7 b + 7 c) / 36`, a sixth of the triangle each side of the line to the centroid.
pub fn cell_centroids(mesh: &Mesh) -> Vec<DVec3> {
    let mut sum = vec![(DVec3::ZERO, 0.0); mesh.positions().len()];
    for (t, tri) in mesh.triangles().iter().enumerate() {
        let p = tri.map(|v| mesh.positions()[v as usize].as_dvec3());
        let third = mesh.triangle_areas()[t] / 3.0;
        for c in 0..3 {
            let centroid = (22.0 * p[c] + 7.0 * (p[(c + 1) % 3] + p[(c + 2) % 3])) / 36.0;
            let (s, w) = &mut sum[tri[c] as usize];
            (*s, *w) = (*s + centroid * third, *w + third);
        }
    }
    sum.iter().zip(mesh.positions()).map(|(&(s, w), p)| if w > 0.0 { s / w } else { p.as_dvec3() }).collect()
}

fn distance2(a: &Features, b: &Features) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

impl Patches {
    /// About `count` patches of `mesh` (as many as it has vertices, if fewer).
    pub fn new(mesh: &Mesh, count: usize) -> Patches {
        let cells = cell_areas(mesh);
        let total: f64 = cells.iter().sum();
        let k = count.clamp(1, mesh.positions().len().max(1));
        let radius = (total / k as f64 / std::f64::consts::PI).sqrt();
        let mut patches = Patches { of_vertex: Vec::new(), centres: Vec::new(), area: vec![0.0; k], cells, radius };
        let f: Vec<Features> = mesh
            .positions()
            .iter()
            .zip(mesh.vertex_normals())
            .map(|(p, n)| patches.features(p.as_dvec3(), n.as_dvec3()))
            .collect();
        patches.centres = farthest_points(&f, k);
        for _ in 0..LLOYD {
            patches.of_vertex = f.par_iter().map(|x| patches.nearest(x)).collect();
            let mut sum = vec![([0.0; 6], 0.0); k];
            for (v, &c) in patches.of_vertex.iter().enumerate() {
                let (s, w) = &mut sum[c as usize];
                (0..6).for_each(|d| s[d] += patches.cells[v] * f[v][d]);
                *w += patches.cells[v];
            }
            for (c, (s, w)) in patches.centres.iter_mut().zip(sum) {
                if w > 0.0 {
                    *c = s.map(|x| x / w);
                }
            }
        }
        for (v, &c) in patches.of_vertex.iter().enumerate() {
            patches.area[c as usize] += patches.cells[v];
        }
        patches
    }

    /// These patches on `mesh`, a rigid move of the mesh they were made on (same vertices and
    /// triangles): each centre the area-weighted mean of its vertices' features there, as the
    /// last k-means step left it on the first mesh.
    pub fn placed_on(&self, mesh: &Mesh) -> Patches {
        let mut sum = vec![([0.0; 6], 0.0); self.len()];
        for (v, (p, n)) in mesh.positions().iter().zip(mesh.vertex_normals()).enumerate() {
            let (s, w) = &mut sum[self.of_vertex[v] as usize];
            let f = self.features(p.as_dvec3(), n.as_dvec3());
            (0..6).for_each(|d| s[d] += self.cells[v] * f[d]);
            *w += self.cells[v];
        }
        let centres =
            sum.iter().zip(&self.centres).map(|((s, w), old)| if *w > 0.0 { s.map(|x| x / w) } else { *old }).collect();
        Patches { centres, ..self.clone() }
    }

    /// Each patch's entry centre on `mesh` (these patches' mesh, or a rigid move of it): the
    /// mean of a point drawn uniformly over its vertices' cells, as the kernel's walks enter
    /// (`cell_centroids`, weighted by the cells).
    pub fn entry_centres(&self, mesh: &Mesh) -> Vec<DVec3> {
        let mut sum = vec![DVec3::ZERO; self.len()];
        for (v, c) in cell_centroids(mesh).into_iter().enumerate() {
            sum[self.of_vertex[v] as usize] += c * self.cells[v];
        }
        sum.iter().zip(&self.area).map(|(&s, &a)| if a > 0.0 { s / a } else { s }).collect()
    }

    /// How many patches.
    pub fn len(&self) -> usize {
        self.centres.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.centres.is_empty()
    }

    /// The unit direction in patch `from`'s tangent plane towards patch `to`'s centre (zero
    /// for the patch itself, or one straight along its normal): the axis along which the
    /// transport kernel reads an entry's sideways tilt (`optics::transport`). It follows a rigid
    /// move, as the centres do.
    pub fn toward(&self, from: usize, to: usize) -> DVec3 {
        let (n, d) = (self.normal(from), self.centre(to) - self.centre(from));
        (d - n * d.dot(n)).normalize_or_zero()
    }

    /// Patch `i`'s centre's position.
    pub fn centre(&self, i: usize) -> DVec3 {
        let c = &self.centres[i];
        DVec3::new(c[0], c[1], c[2])
    }

    /// Patch `i`'s unit mean normal (zero where its normals cancel).
    pub fn normal(&self, i: usize) -> DVec3 {
        let c = &self.centres[i];
        DVec3::new(c[3], c[4], c[5]).normalize_or_zero()
    }

    /// The features of a surface point at `p` with normal `n`.
    pub fn features(&self, p: DVec3, n: DVec3) -> Features {
        let n = n.normalize_or_zero() * self.radius;
        [p.x, p.y, p.z, n.x, n.y, n.z]
    }

    /// The patch whose centre is nearest to `x`.
    pub fn nearest(&self, x: &Features) -> u32 {
        let mut best = (0, f64::INFINITY);
        for (c, centre) in self.centres.iter().enumerate() {
            let d = distance2(centre, x);
            if d < best.1 {
                best = (c, d);
            }
        }
        best.0 as u32
    }

    /// The [`NEIGHBOURS`] patches nearest to `x` (fewer if there are fewer), each with its
    /// blending weight `exp(-d^2 / (BLEND radius)^2)` (`d` the distance in features, floored
    /// above 0; a blend 1.5 radii wide read 0.3 to 1.1 points worse on the bunny's ears, and
    /// on the marble sphere 0.3 to 0.4 better in red and green, 0.9 worse in blue).
    pub fn neighbours(&self, x: &Features) -> Vec<(u32, f64)> {
        let mut near: Vec<(f64, usize)> = self.centres.iter().enumerate().map(|(i, c)| (distance2(c, x), i)).collect();
        let n = NEIGHBOURS.min(near.len());
        near.select_nth_unstable_by(n - 1, |a, b| a.0.total_cmp(&b.0));
        near.truncate(n);
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        let h2 = BLEND * BLEND * self.radius * self.radius;
        near.into_iter().map(|(d2, i)| (i as u32, (-d2 / h2).exp().max(1e-30))).collect()
    }
}

/// `k` points of `f` spread by farthest-point sampling from the first.
fn farthest_points(f: &[Features], k: usize) -> Vec<Features> {
    let mut chosen = vec![f[0]];
    let mut far: Vec<f64> = f.iter().map(|x| distance2(x, &f[0])).collect();
    while chosen.len() < k {
        let (i, _) = far.iter().enumerate().fold((0, -1.0), |b, (i, &d)| if d > b.1 { (i, d) } else { b });
        chosen.push(f[i]);
        far.par_iter_mut().zip(f).for_each(|(d, x)| *d = d.min(distance2(x, &f[i])));
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patches_partition_the_surface_into_about_equal_areas() {
        let mesh = crate::mesh::shapes::sphere(1.0, 24).unwrap();
        let p = Patches::new(&mesh, 32);
        assert_eq!(p.len(), 32);
        let total: f64 = p.area.iter().sum();
        assert!((total - p.cells.iter().sum::<f64>()).abs() < 1e-12 * total);
        let mean = total / 32.0;
        // k-means on a sphere: no patch empty, none over three times the mean.
        assert!(p.area.iter().all(|&a| a > 0.2 * mean && a < 3.0 * mean), "{:?}", p.area);
        // A vertex's own patch is among its neighbours, first or nearly.
        for v in (0..mesh.positions().len()).step_by(37) {
            let x = p.features(mesh.positions()[v].as_dvec3(), mesh.vertex_normals()[v].as_dvec3());
            let near = p.neighbours(&x);
            assert_eq!(near.len(), NEIGHBOURS);
            assert!(near.iter().any(|&(i, _)| i == p.of_vertex[v]));
        }
    }
}

//! The transport kernel of a rigid translucent object (`material.model = "transport"`): the
//! radiative transfer through its own mesh and medium, tabulated between patches of its
//! surface (`mesh::patches`), which corrects the dipole's half-space answer where the object's
//! shape returns light the half-space loses (on a 2 cm marble sphere the dipole is 26% too
//! dark).
//!
//! `W_IJ` is the flux that leaves through patch `I` per unit flux transmitted into patch `J`,
//! entering uniformly over `J` straight in along the inward normal: estimated once by random
//! walks in the mesh (`reference::rte_mesh::kernel`), with no light or camera in it. Per
//! frame, with `Phi_J` the transmitted flux into `J` (the splat's `E_t` times the samples'
//! areas) and `M_d` the dipole's exitance at the vertices:
//!
//! - `F_I = sum_J W_IJ Phi_J / A_I`, the kernel's exitance averaged over `I`;
//! - `D_I = sum_(v in I) A_v M_d(v) / A_I`, the dipole's, alike (`A_v` the vertex's dual cell);
//! - `M(v) = M_d(v) sum_I w_vI F_I / sum_I w_vI D_I` over the vertex's nearest patches with
//!   the weights of `Patches::neighbours`.
//!
//! The dipole keeps the detail under a patch (it follows the irradiance at every sample), the
//! kernel sets each patch's level. Blending the two fluxes before dividing (rather than
//! blending the patches' ratios) keeps a dark patch's large ratio from brightening its lit
//! neighbours. The f32 twin is `glsl/transport.comp`.

use crate::mesh::Mesh;
use crate::mesh::patches::Patches;

/// The kernel of one object (see the module's documentation).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TransportKernel {
    /// The patches it is tabulated between.
    pub patches: Patches,
    /// Per channel, `W_IJ` at `[I * K + J]`, `K` patches.
    pub flux: [Vec<f64>; 3],
    /// Walks per patch and channel it was estimated with.
    pub walks: u64,
}

/// Per patch, RGB.
pub type PerPatch = Vec<[f64; 3]>;

impl TransportKernel {
    /// `Phi_J`: per patch, the transmitted flux of `points`, each (its patch, its area, its
    /// transmitted irradiance `E_t`).
    pub fn patch_flux(&self, points: impl Iterator<Item = (u32, f64, [f64; 3])>) -> PerPatch {
        let mut phi = vec![[0.0; 3]; self.patches.len()];
        for (j, area, e) in points {
            (0..3).for_each(|c| phi[j as usize][c] += area * e[c]);
        }
        phi
    }

    /// `F_I`: per patch, the kernel's exitance averaged over it under the fluxes `phi`.
    pub fn transport_exitance(&self, phi: &[[f64; 3]]) -> PerPatch {
        let k = self.patches.len();
        (0..k)
            .map(|i| {
                [0, 1, 2].map(|c| {
                    let row = &self.flux[c][i * k..(i + 1) * k];
                    row.iter().zip(phi).map(|(w, p)| w * p[c]).sum::<f64>() / self.patches.area[i]
                })
            })
            .collect()
    }

    /// `D_I`: per patch, the dipole's exitance `dipole` (per vertex) averaged over it by the
    /// vertices' `cells` (the mesh's dual cells, or a level of detail's: zero off the level);
    /// 0 where none of its vertices has a cell.
    pub fn dipole_exitance(&self, dipole: &[[f64; 3]], cells: &[f64]) -> PerPatch {
        let (mut d, mut area) = (vec![[0.0; 3]; self.patches.len()], vec![0.0; self.patches.len()]);
        for (v, &i) in self.patches.of_vertex.iter().enumerate() {
            if cells[v] > 0.0 {
                (0..3).for_each(|c| d[i as usize][c] += cells[v] * dipole[v][c]);
                area[i as usize] += cells[v];
            }
        }
        d.iter_mut().zip(&area).for_each(|(d, &a)| d.iter_mut().for_each(|x| *x = if a > 0.0 { *x / a } else { 0.0 }));
        d
    }

    /// `M(v)`: the dipole's `m` at a point with patch neighbours `near` scaled by the ratio of
    /// the blended `F` and `D`; `m` itself where the dipole's blend is not positive.
    pub fn scaled(m: [f64; 3], near: &[(u32, f64)], f: &[[f64; 3]], d: &[[f64; 3]]) -> [f64; 3] {
        [0, 1, 2].map(|c| {
            let (mut sf, mut sd) = (0.0, 0.0);
            for &(i, w) in near {
                sf += w * f[i as usize][c];
                sd += w * d[i as usize][c];
            }
            let r = sf / sd;
            if sd > 0.0 && r.is_finite() { m[c] * r } else { m[c] }
        })
    }

    /// The model's exitance at every vertex from the dipole's `dipole` at the vertices whose
    /// `cells` are positive (the whole mesh's dual cells, or a level of detail's) and the
    /// fluxes `phi` (the f64 twin of `glsl/transport.comp`), each vertex blended from `near`
    /// (per vertex, its `Patches::neighbours`); the others as they are.
    pub fn exitance(
        &self,
        phi: &[[f64; 3]],
        (dipole, cells): (&[[f64; 3]], &[f64]),
        near: &[Vec<(u32, f64)>],
    ) -> Vec<[f64; 3]> {
        let (f, d) = (self.transport_exitance(phi), self.dipole_exitance(dipole, cells));
        (0..dipole.len())
            .map(|v| if cells[v] > 0.0 { Self::scaled(dipole[v], &near[v], &f, &d) } else { dipole[v] })
            .collect()
    }

    /// Its patches on `mesh`, the object as it stands now (`Patches::placed_on`): a rigid move
    /// keeps the kernel, and the patches' centres follow the vertices.
    pub fn placed(&self, mesh: &Mesh) -> Patches {
        self.patches.placed_on(mesh)
    }

    /// Each vertex's patch neighbours on `mesh` (`placed` its patches there).
    pub fn vertex_neighbours(placed: &Patches, mesh: &Mesh) -> Vec<Vec<(u32, f64)>> {
        use rayon::prelude::*;
        mesh.positions()
            .par_iter()
            .zip(mesh.vertex_normals())
            .map(|(p, n)| placed.neighbours(&placed.features(p.as_dvec3(), n.as_dvec3())))
            .collect()
    }

    /// The patch of a sample on `triangle` of `mesh` at `barycentric`: that of the corner
    /// whose dual cell holds it (the largest coordinate), so that the samples split the
    /// transmitted flux between patches as the vertices' cells split the surface.
    pub fn sample_patch(&self, mesh: &Mesh, triangle: u32, barycentric: [f32; 3]) -> u32 {
        let b = barycentric;
        let corner = if b[0] >= b[1] && b[0] >= b[2] {
            0
        } else if b[1] >= b[2] {
            1
        } else {
            2
        };
        self.patches.of_vertex[mesh.triangles()[triangle as usize][corner] as usize]
    }

    /// Bytes of device memory the kernel takes (`W` as f32 RGBA per pair of patches).
    pub fn device_bytes(&self) -> u64 {
        (self.patches.len() as u64).pow(2) * 16
    }
}

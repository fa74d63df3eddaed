//! Ray casting `E_t` on one object's triangles: how deep each triangle's grid goes at every
//! level (its plan, from its base grid) and the grid's values.

use super::source::{Source, grid_index, triangle_point};
use super::{EDGE_EXTRA_DEPTH, NORMAL_SPREAD, STRONG_LIGHT};
use crate::mesh::Mesh;
use crate::mesh::bvh::Bvh;
use crate::reference::{Visibility, light_incidence, transmitted_irradiance_known};
use crate::scene::build::{PreparedObject, PreparedScene, ResolvedMaterial};
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// Each translucent object's [`TrianglePlan`]s (`None` for an opaque object): the base grids
/// ray cast once, for every level.
pub(super) fn plans(scene: &PreparedScene, occluders: &Bvh, eps: f64) -> Vec<Option<Vec<TrianglePlan>>> {
    scene
        .objects
        .iter()
        .map(|o| match &o.material {
            ResolvedMaterial::Translucent { material, .. } => {
                let caster = Caster::new(scene, occluders, o, material.eta, eps);
                Some((0..o.mesh.triangles().len()).into_par_iter().map(|t| caster.plan(&o.mesh, t)).collect())
            }
            ResolvedMaterial::Opaque { .. } => None,
        })
        .collect()
}

/// The lights (by bit, modulo 64) giving at least [`STRONG_LIGHT`] of the total incidence at
/// the mesh's centre: their shadow edges get [`EDGE_EXTRA_DEPTH`] more levels.
fn strong_lights(scene: &PreparedScene, mesh: &Mesh) -> u64 {
    let centre = mesh.positions().iter().map(|p| p.as_dvec3()).sum::<DVec3>() / mesh.positions().len().max(1) as f64;
    let peak: Vec<f64> = scene.lights.iter().map(|l| light_incidence(l, centre).1.max_element()).collect();
    let total: f64 = peak.iter().sum();
    peak.iter().enumerate().filter(|&(_, &p)| p >= STRONG_LIGHT * total).fold(0u64, |m, (i, _)| m | 1u64 << (i % 64))
}

/// What ray casting `E_t` on one object's triangles needs: the scene, its occluders, the
/// object's refractive index and ray offset, its vertex normals and its strong lights.
pub(super) struct Caster<'a> {
    scene: &'a PreparedScene,
    occluders: &'a Bvh,
    eta: f64,
    eps: f64,
    normals: &'a [Vec3],
    /// [`strong_lights`].
    strong: u64,
}

/// How one triangle is refined, from its base grid (ray cast once): its depth at level `l` is
/// `base + l + extra`, and which lights its finer grids ray cast.
#[derive(Clone, Copy, Debug)]
pub(super) struct TrianglePlan {
    /// Grid depth at level 0 before shadow edges: set by how far the shading normal turns.
    base: u32,
    /// [`EDGE_EXTRA_DEPTH`] where a strong light's shadow edge crosses the triangle, else 0.
    extra: u32,
    /// The lights finer grids ray cast, and those known blocked everywhere.
    finer: Visibility,
}

impl TrianglePlan {
    pub(super) fn depth(&self, level: u32) -> u32 {
        self.base + level + self.extra
    }

    /// What the grid at `level` knows without a ray: nothing on the base grid, the base grid's
    /// verdicts on the finer ones.
    pub(super) fn known(&self, level: u32) -> Visibility {
        if self.depth(level) == self.base { Visibility::TRACE_ALL } else { self.finer }
    }
}

impl<'a> Caster<'a> {
    pub(super) fn new(
        scene: &'a PreparedScene,
        occluders: &'a Bvh,
        o: &'a PreparedObject,
        eta: f64,
        eps: f64,
    ) -> Caster<'a> {
        let mesh = &o.mesh;
        Caster { scene, occluders, eta, eps, normals: mesh.vertex_normals(), strong: strong_lights(scene, mesh) }
    }

    /// How triangle `t` of `mesh` is refined at every level: its grid as deep as its normals
    /// and shadow edges ask.
    pub(super) fn plan(&self, mesh: &Mesh, t: usize) -> TrianglePlan {
        let corners = mesh.corners(t);
        let normals = mesh.triangles()[t].map(|i| self.normals[i as usize].as_dvec3());
        let [a, b, c] = normals;
        // E_t follows the shading normal: linear interpolation over a cell whose normals
        // turn by `delta` radians misses about `delta^2 / 8` of it, so cells start small
        // enough that `delta` is at most NORMAL_SPREAD.
        let spread = [a.angle_between(b), b.angle_between(c), c.angle_between(a)].into_iter().fold(0.0, f64::max);
        let base = (spread / NORMAL_SPREAD).log2().ceil().clamp(0.0, 8.0) as u32;
        // Every light is ray cast on the base grid. A light that reaches some of its points
        // and is blocked at others casts a shadow edge across the triangle (the terminator
        // is no edge: E_t falls to zero there continuously, as cos^2); such lights are ray
        // cast on the finer grids, and so are those that face none of the base points (the
        // triangle straddles their terminator, so the base grid says nothing of their
        // shadows; back-facing points cost no ray). The others keep the base grid's
        // verdict, so a shadow narrower than the base grid that touches none of its points
        // is missed at every level.
        let (reached, blocked) = self.verdicts(&corners, normals, base);
        let edges = reached & blocked;
        let unknown = !(reached | blocked);
        TrianglePlan {
            base,
            extra: if edges & self.strong != 0 { EDGE_EXTRA_DEPTH } else { 0 },
            finer: Visibility { trace: edges | unknown, blocked: blocked & !reached },
        }
    }

    /// Triangle `t` of `mesh` as a source at `level`, refined as `plan` says, and with `keep`
    /// what its rays found ([`Shadows`]), so that the same source can be made again without a
    /// ray ([`Caster::source_again`]); none where the scene has more lights than a mask holds.
    pub(super) fn source_and_shadows(
        &self,
        mesh: &Mesh,
        t: usize,
        plan: &TrianglePlan,
        level: u32,
        keep: bool,
    ) -> (Source, Option<Shadows>) {
        let corners = mesh.corners(t);
        let normals = mesh.triangles()[t].map(|i| self.normals[i as usize].as_dvec3());
        let depth = plan.depth(level);
        let known = plan.known(level);
        let (grid, blocked) = self.grid(&corners, normals, depth, |_| known);
        let shadows = (keep && self.scene.lights.len() <= 64).then(|| Shadows::pack(known.trace, &blocked));
        (Source::new(corners, depth, grid, mesh.triangle_areas()[t]), shadows)
    }

    /// The source [`Caster::source_and_shadows`] made, made again for its pieces: from its
    /// `shadows` without a ray, else ray cast again. The same bits.
    pub(super) fn source_again(
        &self,
        mesh: &Mesh,
        t: usize,
        plan: &TrianglePlan,
        level: u32,
        shadows: Option<&Shadows>,
    ) -> Source {
        let corners = mesh.corners(t);
        let normals = mesh.triangles()[t].map(|i| self.normals[i as usize].as_dvec3());
        let depth = plan.depth(level);
        let known = plan.known(level);
        let at = |k: usize| match shadows {
            Some(shadows) => Visibility { trace: 0, blocked: (known.blocked & !known.trace) | shadows.blocked(k) },
            None => known,
        };
        let (grid, _) = self.grid(&corners, normals, depth, at);
        Source::new(corners, depth, grid, mesh.triangle_areas()[t])
    }

    /// `E_t` at the grid points of a triangle's grid at `depth` (at [`grid_index`]), and the
    /// lights blocked at each. Normals are interpolated from the corners'; `known(k)` says which
    /// lights need no ray at point `k`.
    fn grid(
        &self,
        corners: &[DVec3; 3],
        normals: [DVec3; 3],
        depth: u32,
        known: impl Fn(usize) -> Visibility,
    ) -> (Vec<DVec3>, Vec<u64>) {
        let n = 1usize << depth;
        let mut grid = vec![DVec3::ZERO; (n + 1) * (n + 2) / 2];
        let mut blocked = vec![0u64; grid.len()];
        for i in 0..=n {
            for j in 0..=n - i {
                let k = grid_index(i, j, n);
                let (e, _, b) = self.at(corners, normals, i as f64 / n as f64, j as f64 / n as f64, known(k));
                (grid[k], blocked[k]) = (e, b);
            }
        }
        (grid, blocked)
    }

    /// The lights that reached and that were blocked at any point of the grid at `depth` or at
    /// the centroid, every light ray cast.
    fn verdicts(&self, corners: &[DVec3; 3], normals: [DVec3; 3], depth: u32) -> (u64, u64) {
        let n = 1usize << depth;
        let (mut reached, mut blocked) = (0u64, 0u64);
        let centroid = [(n as f64 / 3.0, n as f64 / 3.0)];
        let points = (0..=n).flat_map(|i| (0..=n - i).map(move |j| (i as f64, j as f64))).chain(centroid);
        for (i, j) in points {
            let (_, r, b) = self.at(corners, normals, i / n as f64, j / n as f64, Visibility::TRACE_ALL);
            (reached, blocked) = (reached | r, blocked | b);
        }
        (reached, blocked)
    }

    /// `E_t` at `(u, v)` of a triangle, with the lights that reached and that were blocked.
    fn at(&self, corners: &[DVec3; 3], [a, b, c]: [DVec3; 3], u: f64, v: f64, known: Visibility) -> (DVec3, u64, u64) {
        let p = triangle_point(corners, u, v);
        let normal = a * (1.0 - u - v) + b * u + c * v;
        transmitted_irradiance_known(self.scene, self.occluders, p, normal, self.eta, self.eps, known)
    }
}

/// What the rays of one triangle's grid found: per grid point, which of the lights it ray cast
/// were blocked, packed a bit a light (`known.trace`'s lights only; the others the plan knows).
pub(super) struct Shadows {
    /// The traced lights' bits, in order.
    lights: Vec<u64>,
    bits: Vec<u64>,
}

impl Shadows {
    fn pack(trace: u64, blocked: &[u64]) -> Shadows {
        let lights: Vec<u64> = (0..64).map(|i| 1u64 << i).filter(|b| trace & b != 0).collect();
        let k = lights.len();
        let mut bits = vec![0u64; (blocked.len() * k).div_ceil(64)];
        for (p, mask) in blocked.iter().enumerate() {
            for (j, light) in lights.iter().enumerate() {
                if mask & light != 0 {
                    let at = p * k + j;
                    bits[at / 64] |= 1 << (at % 64);
                }
            }
        }
        Shadows { lights, bits }
    }

    /// The traced lights blocked at grid point `p`.
    fn blocked(&self, p: usize) -> u64 {
        let k = self.lights.len();
        self.lights.iter().enumerate().fold(0, |m, (j, light)| {
            let at = p * k + j;
            if self.bits[at / 64] >> (at % 64) & 1 != 0 { m | light } else { m }
        })
    }

    /// Bytes these shadows take for a grid of `points` points and `traced` lights.
    pub(super) fn bytes(points: usize, traced: u64) -> u64 {
        ((points * traced.count_ones() as usize).div_ceil(64) * 8 + size_of::<Shadows>()) as u64
    }
}

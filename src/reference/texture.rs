//! The texture-space gather in f64 (`render.gather = "texture"`), twin of
//! glsl/gather_texture.comp (`render::gather_texture` has the estimator): the local window
//! summed exactly, the rest estimated from texels drawn by power with the same random numbers.
//! The sum tree the texels are drawn from is built and descended in f32 in the GPU's order, so
//! that both draw the same texels; every value the estimator adds up is f64.
//!
//! [`expected`] is the estimator's expectation, the dipole sum over the texels with the near
//! field blended over the window: what the mean over many seeds approaches.

use super::{near_blend, near_kept, per_translucent_object};
use crate::mesh::atlas::{Atlas, tree_levels, tree_nodes};
use crate::optics::Dipole;
use crate::optics::kernel;
use crate::scene::build::{PreparedObject, PreparedScene};
use glam::DVec3;
use rayon::prelude::*;

/// PCG hash (Jarzynski and Olano 2020, "Hash Functions for GPU Rendering"): `pcg` in
/// glsl/gather_texture.comp.
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The uniform number in [0, 1) (24 bits, exact in f32) that receiver `vertex` (object-relative)
/// uses for sample `k` at depth `depth` under `seed`: `random01` in glsl/gather_texture.comp.
pub fn random(vertex: u32, k: u32, depth: u32, seed: u32) -> f32 {
    let h = pcg(vertex.wrapping_add(pcg(k.wrapping_add(pcg(depth.wrapping_add(pcg(seed)))))));
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The 4-ary sum tree of texel power, as stage 0 of glsl/gather_texture.comp builds it (f32, the
/// same order of additions).
pub struct PowerTree {
    levels: u32,
    /// Per depth 0..levels, its nodes (`4^depth` of them).
    nodes: Vec<Vec<f32>>,
    leaves: Vec<f32>,
}

impl PowerTree {
    /// The tree over texels with irradiance `e` and area `area` (both as the GPU holds them:
    /// f32): leaf power `((e_r + e_g) + e_b) area`.
    pub fn new(e: &[[f32; 3]], area: &[f32]) -> PowerTree {
        let leaves: Vec<f32> = e.iter().zip(area).map(|(e, a)| ((e[0] + e[1]) + e[2]) * a).collect();
        let levels = tree_levels(leaves.len());
        let mut nodes: Vec<Vec<f32>> = vec![Vec::new(); levels as usize];
        for d in (0..levels as usize).rev() {
            let below = if d + 1 < levels as usize { &nodes[d + 1] } else { &leaves };
            let child = |c: usize| below.get(c).copied().unwrap_or(0.0);
            nodes[d] = (0..1usize << (2 * d))
                .map(|i| ((child(4 * i) + child(4 * i + 1)) + child(4 * i + 2)) + child(4 * i + 3))
                .collect();
        }
        debug_assert_eq!(nodes.iter().map(Vec::len).sum::<usize>(), tree_nodes(levels));
        PowerTree { levels, nodes, leaves }
    }

    fn child(&self, d: usize, node: usize, j: usize) -> f32 {
        let c = 4 * node + j;
        let below = if d + 1 < self.levels as usize { &self.nodes[d + 1] } else { &self.leaves };
        below.get(c).copied().unwrap_or(0.0)
    }

    /// Draw a leaf with the numbers `u(depth)`: its index and probability, or `None` when the
    /// tree has no power (`draw` in glsl/gather_texture.comp).
    pub fn draw(&self, u: impl Fn(u32) -> f32) -> Option<(usize, f64)> {
        let (mut node, mut p) = (0usize, 1.0f64);
        for d in 0..self.levels {
            let w = [0, 1, 2, 3].map(|j| self.child(d as usize, node, j));
            let total = ((w[0] + w[1]) + w[2]) + w[3];
            if total.is_nan() || total <= 0.0 {
                return None;
            }
            let t = u(d) * total;
            let (c1, c2) = (w[0] + w[1], (w[0] + w[1]) + w[2]);
            let mut j = if t < w[0] {
                0
            } else if t < c1 {
                1
            } else if t < c2 {
                2
            } else {
                3
            };
            while w[j] <= 0.0 && j > 0 {
                j -= 1;
            }
            p *= f64::from(w[j]) / f64::from(total);
            node = 4 * node + j;
        }
        (self.levels > 0 || self.leaves.first().is_some_and(|&l| l > 0.0)).then_some((node, p))
    }
}

/// One object's data: its atlas, dipoles, texels (position, area, irradiance) and power tree.
struct TextureGather<'a> {
    atlas: &'a Atlas,
    dipoles: &'a [Dipole; 3],
    positions: Vec<DVec3>,
    areas: Vec<f64>,
    e: Vec<[f64; 3]>,
    radii: [f64; 3],
    tree: PowerTree,
    /// The local window's half-width in texels.
    h: u32,
}

impl<'a> TextureGather<'a> {
    fn new(o: &'a PreparedObject, atlas: &'a Atlas, dipoles: &'a [Dipole; 3], irradiance: &[[f64; 3]]) -> Self {
        // As the GPU holds them: f32 irradiance and area.
        let e32: Vec<[f32; 3]> = irradiance.iter().map(|e| e.map(|v| v as f32)).collect();
        let a32: Vec<f32> = o.samples.iter().map(|s| s.area as f32).collect();
        TextureGather {
            atlas,
            dipoles,
            positions: o.samples.iter().map(|s| s.position.as_dvec3()).collect(),
            areas: a32.iter().map(|&a| f64::from(a)).collect(),
            e: e32.iter().map(|e| e.map(f64::from)).collect(),
            radii: o.near_blend_radii(),
            tree: PowerTree::new(&e32, &a32),
            h: o.window_radius().unwrap_or(1),
        }
    }

    fn far(&self, x: DVec3, i: usize) -> [f64; 3] {
        let r = x.distance(self.positions[i]);
        [0, 1, 2].map(|c| self.e[i][c] * kernel::far_kernel(&self.dipoles[c], r, self.areas[i]))
    }

    fn in_window(&self, own: [u32; 2], at: [u32; 2]) -> bool {
        own[0].abs_diff(at[0]) <= self.h && own[1].abs_diff(at[1]) <= self.h
    }

    /// The local term at vertex `v` (position `x`): far sum and blended near field over the
    /// window, times the share kept beside open boundaries `boundary` away.
    fn local(&self, x: DVec3, own: [u32; 2], boundary: [f32; 2]) -> [f64; 3] {
        let (h, side) = (i64::from(self.h), i64::from(self.atlas.resolution));
        let (mut far, mut near) = ([0.0; 3], Vec::new());
        for y in (i64::from(own[1]) - h..=i64::from(own[1]) + h).filter(|y| (0..side).contains(y)) {
            for tx in (i64::from(own[0]) - h..=i64::from(own[0]) + h).filter(|x| (0..side).contains(x)) {
                let Some(i) = self.atlas.texel_at(tx as u32, y as u32) else { continue };
                let i = i as usize;
                let f = self.far(x, i);
                (0..3).for_each(|c| far[c] += f[c]);
                let b = kernel::B_PER_SQRT_AREA * self.areas[i].sqrt();
                let e = self.e[i];
                near.push((
                    self.positions[i],
                    self.areas[i],
                    [0, 1, 2].map(|c| e[c] * kernel::near_energy(&self.dipoles[c], b)),
                ));
            }
        }
        let (blended, mean_area) = near_blend(x, &near, self.radii);
        let kept = near_kept(self.dipoles, mean_area, boundary);
        [0, 1, 2].map(|c| (far[c] + blended[c] * kept[c]).max(0.0))
    }

    /// The estimate at vertex `v` with `samples` draws under `seed`.
    fn at(&self, v: usize, x: DVec3, boundary: [f32; 2], samples: u32, seed: u32) -> [f64; 3] {
        let own = self.atlas.vertex_texel[v];
        let local = self.local(x, own, boundary);
        let mut global = [0.0; 3];
        for k in 0..samples {
            let Some((i, p)) = self.tree.draw(|d| random(v as u32, k, d, seed)) else { continue };
            if self.in_window(own, self.atlas.texels[i].coord) {
                continue;
            }
            let f = self.far(x, i);
            (0..3).for_each(|c| global[c] += f[c] / p);
        }
        [0, 1, 2].map(|c| (local[c] + global[c] / f64::from(samples.max(1))).max(0.0))
    }

    /// The expectation at vertex `v`: the local term plus every texel outside the window.
    fn expected_at(&self, v: usize, x: DVec3, boundary: [f32; 2]) -> [f64; 3] {
        let own = self.atlas.vertex_texel[v];
        let mut m = self.local(x, own, boundary);
        for (i, t) in self.atlas.texels.iter().enumerate() {
            if !self.in_window(own, t.coord) && self.tree.leaves[i] > 0.0 {
                let f = self.far(x, i);
                (0..3).for_each(|c| m[c] += f[c]);
            }
        }
        m
    }
}

/// Radiant exitance at every vertex of every object (zero for opaque ones and objects without
/// an atlas) by the texture gather with `samples` draws per receiver under `seed` (0 is what
/// the GPU's frames use), from per-sample transmitted irradiance in scene order.
pub fn gather(scene: &PreparedScene, irradiance: &[[f64; 3]], samples: u32, seed: u32) -> Vec<Vec<[f64; 3]>> {
    per_object(scene, irradiance, |g, v, x, b| g.at(v, x, b, samples, seed))
}

/// The texture gather's expectation at every vertex ([`gather`] averaged over every seed).
pub fn expected(scene: &PreparedScene, irradiance: &[[f64; 3]]) -> Vec<Vec<[f64; 3]>> {
    per_object(scene, irradiance, |g, v, x, b| g.expected_at(v, x, b))
}

fn per_object(
    scene: &PreparedScene,
    irradiance: &[[f64; 3]],
    f: impl Fn(&TextureGather, usize, DVec3, [f32; 2]) -> [f64; 3] + Sync,
) -> Vec<Vec<[f64; 3]>> {
    per_translucent_object(scene, |o, dipoles, first| {
        let Some(atlas) = &o.atlas else { return vec![[0.0; 3]; o.mesh.positions().len()] };
        let g = TextureGather::new(o, atlas, dipoles, &irradiance[first..first + o.samples.len()]);
        let boundary = o.mesh.boundary_distances();
        o.mesh.positions().par_iter().enumerate().map(|(v, x)| f(&g, v, x.as_dvec3(), boundary[v])).collect()
    })
}

//! The hierarchical gather in f64 (`render.gather = "hierarchical"`), twin of
//! glsl/gather_tree.comp and glsl/common/tree.glsl: the same hierarchy
//! (`PreparedObject::sample_tree`), the same node aggregates, the same traversal order and the
//! same criteria, so the GPU can be tested against it node decision for node decision.

use super::{near_blend, per_translucent_object};
use crate::optics::Dipole;
use crate::optics::kernel::{self, B_PER_SQRT_AREA, TREE_PRUNE_FRACTION};
use crate::sampling::{SampleTree, TreeNode};
use crate::scene::build::PreparedScene;
use glam::DVec3;
use rayon::prelude::*;

/// What stage 0 of glsl/gather_tree.comp computes per node: transmitted power `sum E_i A_i`
/// per channel and the power-weighted centroid (the bounding centre when unlit).
#[derive(Clone, Copy, Debug)]
pub struct NodePower {
    /// `sum E_i A_i` per channel.
    pub power: [f64; 3],
    /// Centroid weighted by each sample's power summed over channels.
    pub centroid: DVec3,
}

/// Stage 0: every node's power and centroid, from per-sample transmitted irradiance `e` and
/// the samples' positions and areas (the object's own sample order).
pub fn node_power(tree: &SampleTree, positions: &[DVec3], areas: &[f64], e: &[[f64; 3]]) -> Vec<NodePower> {
    tree.nodes
        .iter()
        .map(|n| {
            let center = center_of(n);
            let (mut power, mut offset, mut weight) = ([0.0; 3], DVec3::ZERO, 0.0);
            for &s in &tree.order[n.first as usize..(n.first + n.count) as usize] {
                let s = s as usize;
                let p = e[s].map(|v| v * areas[s]);
                let w = p[0] + p[1] + p[2];
                for c in 0..3 {
                    power[c] += p[c];
                }
                offset += w * (positions[s] - center);
                weight += w;
            }
            NodePower { power, centroid: if weight > 0.0 { center + offset / weight } else { center } }
        })
        .collect()
}

fn center_of(n: &TreeNode) -> DVec3 {
    glam::Vec3::from(n.center).as_dvec3()
}

/// Stage 1 at one receiver `x` of the group bounded by `group` (centre, radius): the far sum
/// over the hierarchy with nodes used whole when `A < epsilon dist^2` beyond every near-blend
/// radius (`dist` from the group's sphere), leaves summed sample by sample, nodes pruned when
/// they can add at most `TREE_PRUNE_FRACTION` of the object's mean exitance; plus the near field
/// blended over the visited leaves (the nearest sample's where no weight reaches).
#[allow(clippy::too_many_arguments)]
pub fn gather_at(
    x: DVec3,
    group: ([f32; 3], f32),
    tree: &SampleTree,
    power: &[NodePower],
    dipoles: &[Dipole; 3],
    positions: &[DVec3],
    areas: &[f64],
    e: &[[f64; 3]],
    epsilon: f64,
) -> [f64; 3] {
    let mut far = [0.0f64; 3];
    let mut near = Vec::new();
    let root_area = (tree.nodes[0].area as f64).max(1e-30);
    // epsilon = 0 prunes nothing either: the exact flat sum.
    let negligible: [f64; 3] = [0, 1, 2].map(|c| {
        if epsilon > 0.0 { TREE_PRUNE_FRACTION * dipoles[c].r_d_total() * power[0].power[c] / root_area } else { -1.0 }
    });
    let (group_center, group_radius) = (glam::Vec3::from(group.0).as_dvec3(), group.1 as f64);
    let mut i = 0;
    while i < tree.nodes.len() {
        let n = &tree.nodes[i];
        let dist = group_center.distance(center_of(n)) - n.radius as f64 - group_radius;
        let beyond_blend = dist > n.reach as f64;
        if beyond_blend && (n.area as f64) < epsilon * dist * dist {
            let p = &power[i];
            let r = x.distance(p.centroid);
            let mean_area = n.area as f64 / n.count as f64;
            let b = B_PER_SQRT_AREA * mean_area.sqrt();
            for c in 0..3 {
                far[c] += p.power[c] * kernel::r_d_far(&dipoles[c], r, b);
            }
            i = n.skip as usize;
        } else if n.leaf {
            for &s in &tree.order[n.first as usize..(n.first + n.count) as usize] {
                let s = s as usize;
                let r = x.distance(positions[s]);
                for c in 0..3 {
                    far[c] += e[s][c] * kernel::far_kernel(&dipoles[c], r, areas[s]);
                }
                let b = B_PER_SQRT_AREA * areas[s].sqrt();
                near.push((positions[s], areas[s], [0, 1, 2].map(|c| e[s][c] * kernel::near_energy(&dipoles[c], b))));
            }
            i = n.skip as usize;
        } else if beyond_blend && (0..3).all(|c| power[i].power[c] * dipoles[c].r_d(dist) <= negligible[c]) {
            i = n.skip as usize;
        } else {
            i += 1;
        }
    }
    let mut blended = near_blend(x, &near);
    if !near.iter().any(|(p, area, _)| kernel::near_blend_weight(x.distance(*p), *area) > 0.0) {
        // No weight reached x: the nearest sample of the whole object, as the flat sum takes it.
        let nearest = (0..positions.len())
            .min_by(|&a, &b| x.distance(positions[a]).total_cmp(&x.distance(positions[b])).then(a.cmp(&b)));
        if let Some(s) = nearest {
            let b = B_PER_SQRT_AREA * areas[s].sqrt();
            blended = [0, 1, 2].map(|c| e[s][c] * kernel::near_energy(&dipoles[c], b));
        }
    }
    [0, 1, 2].map(|c| (far[c] + blended[c]).max(0.0))
}

/// Radiant exitance at every vertex of every object (zero for opaque ones) by the hierarchical
/// gather with solid-angle bound `epsilon`, from per-sample transmitted irradiance in scene
/// order. `epsilon = 0` is [`super::gather`]'s flat sum.
pub fn gather(scene: &PreparedScene, irradiance: &[[f64; 3]], epsilon: f64) -> Vec<Vec<[f64; 3]>> {
    per_translucent_object(scene, |o, dipoles, first| {
        let tree = o.sample_tree();
        let positions: Vec<DVec3> = o.samples.iter().map(|s| s.position.as_dvec3()).collect();
        let areas: Vec<f64> = o.samples.iter().map(|s| s.area).collect();
        let e = &irradiance[first..first + o.samples.len()];
        let power = node_power(&tree, &positions, &areas, e);
        if tree.nodes.is_empty() {
            return vec![[0.0; 3]; o.mesh.positions().len()];
        }
        let groups = o.receiver_groups();
        let mesh = o.mesh.positions();
        let mut exitance = vec![[0.0; 3]; mesh.len()];
        let computed: Vec<(usize, [f64; 3])> = groups
            .order
            .par_iter()
            .enumerate()
            .map(|(k, &v)| {
                let x = mesh[v as usize].as_dvec3();
                let m = gather_at(x, groups.group_of(k), &tree, &power, dipoles, &positions, &areas, e, epsilon);
                (v as usize, m)
            })
            .collect();
        for (v, m) in computed {
            exitance[v] = m;
        }
        exitance
    })
}

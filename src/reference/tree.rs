//! The hierarchical gather in f64 (`render.gather = "hierarchical"`), twin of
//! glsl/gather_tree.comp: the same hierarchy (`PreparedObject::sample_tree`), the same receiver
//! groups and cuts (`PreparedObject::gather_cuts`), the same node aggregates, so the GPU can be
//! tested against it item for item.

use super::{near_blend, per_translucent_object};
use crate::optics::Dipole;
use crate::optics::kernel::{self, B_PER_SQRT_AREA};
use crate::sampling::{NODE_ITEM, SampleTree, TreeNode};
use crate::scene::build::PreparedScene;
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// What stage 0 of glsl/gather_tree.comp computes per node: transmitted power `sum E_i A_i`
/// per channel, the power-weighted centroid (the bounding centre when unlit) and the
/// power-weighted covariance of the members about it.
#[derive(Clone, Copy, Debug)]
pub struct NodePower {
    /// `sum E_i A_i` per channel.
    pub power: [f64; 3],
    /// Centroid weighted by each sample's power summed over channels.
    pub centroid: DVec3,
    /// Covariance of the members' positions about the centroid, with the same weights.
    pub covariance: DMat3,
}

/// Stage 0: every node's power and centroid, from per-sample transmitted irradiance `e` and
/// the samples' positions and areas (the object's own sample order). Each node straight from its
/// members, where the GPU combines two children's (the same sums, in another order).
pub fn node_power(tree: &SampleTree, positions: &[DVec3], areas: &[f64], e: &[[f64; 3]]) -> Vec<NodePower> {
    tree.nodes
        .iter()
        .map(|n| {
            let center = center_of(n);
            let members = &tree.order[n.first as usize..(n.first + n.count) as usize];
            let (mut power, mut offset, mut weight) = ([0.0; 3], DVec3::ZERO, 0.0);
            for &s in members {
                let s = s as usize;
                let p = e[s].map(|v| v * areas[s]);
                let w = p[0] + p[1] + p[2];
                for c in 0..3 {
                    power[c] += p[c];
                }
                offset += w * (positions[s] - center);
                weight += w;
            }
            if weight <= 0.0 {
                return NodePower { power, centroid: center, covariance: DMat3::ZERO };
            }
            let centroid = center + offset / weight;
            let mut covariance = DMat3::ZERO;
            for &s in members {
                let s = s as usize;
                let w = e[s].iter().sum::<f64>() * areas[s];
                let y = positions[s] - centroid;
                covariance += DMat3::from_cols(y * y.x, y * y.y, y * y.z) * (w / weight);
            }
            NodePower { power, centroid, covariance }
        })
        .collect()
}

fn center_of(n: &TreeNode) -> DVec3 {
    glam::Vec3::from(n.center).as_dvec3()
}

/// One object's data for stage 1 (`TreeGather::at`): its hierarchy and node powers
/// (`node_power`), its channels' dipoles and near-blend radius factors
/// (`PreparedObject::near_blend_radii`), and its samples' positions, areas and transmitted
/// irradiance in the object's own sample order.
#[derive(Clone, Copy)]
pub struct TreeGather<'a> {
    /// The hierarchy over the object's samples.
    pub tree: &'a SampleTree,
    /// Stage 0's aggregate of each node.
    pub power: &'a [NodePower],
    /// The R, G, B dipoles in scene units.
    pub dipoles: &'a [Dipole; 3],
    /// Sample positions.
    pub positions: &'a [DVec3],
    /// Sample areas.
    pub areas: &'a [f64],
    /// Per-sample transmitted irradiance.
    pub e: &'a [[f64; 3]],
    /// Each channel's near-blend radius factor.
    pub radii: [f64; 3],
}

impl TreeGather<'_> {
    /// Stage 1 at one receiver `x` whose group's cut is `items` (`sampling::SampleTree::cut`): a
    /// sample's far kernel and near exitance as in the flat sum, a node's power times the cluster
    /// kernel (`kernel::r_d_far_cluster`: its centroid, the `b` of its mean area, its spread); the
    /// near field blended over the listed samples with each channel's radius factor `radii` (the
    /// nearest sample of the object where no weight reaches), times the share kept beside open
    /// boundaries `boundary` away (`super::near_kept`).
    pub fn at(&self, x: DVec3, items: &[u32], boundary: [f32; 2]) -> [f64; 3] {
        let TreeGather { tree, power, dipoles, positions, areas, e, radii } = *self;
        let mut far = [0.0f64; 3];
        let mut near = Vec::new();
        for &item in items {
            if item & NODE_ITEM != 0 {
                let i = (item & !NODE_ITEM) as usize;
                let n = &tree.nodes[i];
                // As the GPU packs it: the f32 area over the count.
                let mean_area = (n.area / n.count as f32) as f64;
                let b = B_PER_SQRT_AREA * mean_area.sqrt();
                let u = x - power[i].centroid;
                let cov = &power[i].covariance;
                let w = u.normalize_or_zero();
                let (tr_cov, axial_cov) = (cov.x_axis.x + cov.y_axis.y + cov.z_axis.z, w.dot(*cov * w));
                for c in 0..3 {
                    far[c] +=
                        power[i].power[c] * kernel::r_d_far_cluster(&dipoles[c], u.length(), b, tr_cov, axial_cov);
                }
            } else {
                let s = item as usize;
                let r = x.distance(positions[s]);
                for c in 0..3 {
                    far[c] += e[s][c] * kernel::far_kernel(&dipoles[c], r, areas[s]);
                }
                let b = B_PER_SQRT_AREA * areas[s].sqrt();
                near.push((positions[s], areas[s], [0, 1, 2].map(|c| e[s][c] * kernel::near_energy(&dipoles[c], b))));
            }
        }
        let (blended, mean_area) = near_blend(x, &near, radii);
        let kept = super::near_kept(dipoles, mean_area, boundary);
        let mut blended = [0, 1, 2].map(|c| blended[c] * kept[c]);
        // A channel no weight reached: the nearest sample of the whole object, as the flat sum takes it.
        let nearest = || {
            (0..positions.len())
                .min_by(|&a, &b| x.distance(positions[a]).total_cmp(&x.distance(positions[b])).then(a.cmp(&b)))
        };
        if let Some(s) = mean_area.iter().any(Option::is_none).then(nearest).flatten() {
            let b = B_PER_SQRT_AREA * areas[s].sqrt();
            for c in (0..3).filter(|&c| mean_area[c].is_none()) {
                blended[c] = e[s][c] * kernel::near_energy(&dipoles[c], b);
            }
        }
        [0, 1, 2].map(|c| (far[c] + blended[c]).max(0.0))
    }
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
        let groups = o.receiver_groups();
        let mesh = o.mesh.positions();
        let receivers: Vec<DVec3> = mesh.iter().map(|p| p.as_dvec3()).collect();
        let cuts = o.gather_cuts(&tree, &groups, &receivers, epsilon);
        let boundary = o.mesh.boundary_distances();
        let object = TreeGather {
            tree: &tree,
            power: &power,
            dipoles,
            positions: &positions,
            areas: &areas,
            e,
            radii: o.near_blend_radii(),
        };
        let computed: Vec<(usize, [f64; 3])> = groups
            .order
            .par_iter()
            .enumerate()
            .map(|(k, &v)| {
                let x = mesh[v as usize].as_dvec3();
                let items = cuts.of(k);
                (v as usize, object.at(x, items, boundary[v as usize]))
            })
            .collect();
        let mut exitance = vec![[0.0; 3]; mesh.len()];
        for (v, m) in computed {
            exitance[v] = m;
        }
        exitance
    })
}

//! The between-points single scattering's data, packed once with the scene's GPU data: each
//! object's kernel tables (`optics::beam_table`), packed as f16 cells, and each receiver's walk
//! of the sample hierarchy. `beam_gather` is the pass that reads them.

use super::records::BeamReceiverRecord;
use crate::optics::beam_table::{self, BeamTable};
use crate::sampling::SampleTree;
use crate::scene::build::{PreparedObject, PreparedScene, ResolvedMaterial};
use glam::DVec3;
use rayon::prelude::*;

/// One object's between-points channels and where their table lies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectBeams {
    /// Bit `c`: channel `c` takes single scattering between points.
    pub channels: u32,
    /// Its tables' base in `GpuScene::beam_tables` (uvec4 entries, `pack_tables`).
    pub table: u32,
    /// `sigma_t'` per channel, scene units: a distance in mean free paths is the table's
    /// `rho` (the f64 twin reads it; the shader needs only the shared distance axis).
    pub sigma_t: [f32; 3],
    /// The critical cosine inside (`beam_table::critical_cosine`).
    pub mu_c: f32,
    /// `R1(1)` per channel (`BeamTable::normal_total`).
    pub normal_total: [f32; 3],
    /// How far a sample reaches, in scene units: `beam_table::REACH_MFP` mean free paths of the
    /// longest of its channels.
    pub reach: f32,
    /// The tables' smoothing window radius in scene units (`beam_table::WINDOW` footprint
    /// radii): the tabulated kernel is smooth on this scale, so a node this much smaller may
    /// stand in for its members however near the receiver.
    pub window: f32,
    /// `render.beam_opening`: a node whose radius is under this times its distance from the
    /// receiver (or times `window`, when the receiver is nearer) stands in for its members:
    /// their summed power and area at their area-weighted centroid, with their mean normal and
    /// power-weighted mean beam. 0 is the sum over every sample within reach.
    pub opening: f32,
    /// Whether stage 1 reads each receiver's walk from `GpuScene::beam_items` (every vertex's,
    /// so at any level of detail) rather than taking it each frame: set by [`pack_tables`],
    /// within `render.beam_walk_mib`.
    pub lists: bool,
}

/// The tables of object `o`'s between-points channels for its samples' mean footprint, all
/// with the same reach in scene units, and its `ObjectBeams` with its table at `base` and the
/// walk's `opening` (`render.beam_opening`); `None` when no channel of it takes the model.
pub fn object_tables(o: &PreparedObject, base: usize, opening: f32) -> Option<(ObjectBeams, [Option<BeamTable>; 3])> {
    let single = o.single_channels();
    let ResolvedMaterial::Translucent { dipoles, .. } = &o.material else { return None };
    if !single.contains(&true) || o.samples.is_empty() {
        return None;
    }
    let mean_area = o.samples.iter().map(|s| s.area).sum::<f64>() / o.samples.len() as f64;
    let radius = (mean_area / std::f64::consts::PI).sqrt();
    let longest = (0..3).filter(|&c| single[c]).map(|c| 1.0 / dipoles[c].sigma_t_prime).fold(0.0, f64::max);
    let reach = beam_table::REACH_MFP * longest;
    let curvature = mean_curvature(&o.mesh);
    let tables = [0, 1, 2].map(|c| {
        let d = &dipoles[c];
        let (footprint, reach, bend) = (radius * d.sigma_t_prime, reach * d.sigma_t_prime, d.sigma_t_prime / curvature);
        single[c].then(|| BeamTable::new(d.alpha_prime, d.eta, footprint, reach, bend))
    });
    let beams = ObjectBeams {
        channels: (0..3).filter(|&c| single[c]).map(|c| 1 << c).sum(),
        table: base as u32,
        sigma_t: dipoles.map(|d| d.sigma_t_prime as f32),
        mu_c: beam_table::critical_cosine(dipoles[0].eta) as f32,
        normal_total: tables.each_ref().map(|t| t.as_ref().map_or(0.0, |t| t.normal_total as f32)),
        reach: reach as f32,
        window: (beam_table::WINDOW * radius) as f32,
        opening,
        lists: false,
    };
    Some((beams, tables))
}

/// The mesh's mean normal curvature (scene units), `(n_i - n_j) . (x_i - x_j) / |x_i - x_j|^2`
/// over its edges weighted by their length: `1 / R` on a sphere of radius `R`, 0 on a plane; 0
/// where it comes out negative (a concave mean: the tables are the plane's).
pub fn mean_curvature(mesh: &crate::mesh::Mesh) -> f64 {
    let (p, n) = (mesh.positions(), mesh.vertex_normals());
    let (mut sum, mut weight) = (0.0, 0.0);
    for t in mesh.triangles() {
        for k in 0..3 {
            let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let d = (p[i] - p[j]).as_dvec3();
            let len = d.length();
            if len > 0.0 {
                sum += (n[i] - n[j]).as_dvec3().dot(d) / len;
                weight += len;
            }
        }
    }
    if weight > 0.0 { (sum / weight).max(0.0) } else { 0.0 }
}

/// What the walk of a sample hierarchy sums next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WalkItem {
    /// A node standing in for its members.
    Node(usize),
    /// One sample (its index in the object's samples).
    Sample(usize),
}

/// Where the walk of `tree` about receiver `x` goes, as glsl/beam_gather.comp takes it: nodes
/// within `beams.reach` whose radius is under `beams.opening` times their distance (or times
/// `beams.window`, when `x` is nearer) are visited whole, leaves nearer give their samples.
pub fn walk(tree: &SampleTree, x: DVec3, beams: &ObjectBeams, mut visit: impl FnMut(WalkItem)) {
    let (reach, opening, window) = (f64::from(beams.reach), f64::from(beams.opening), f64::from(beams.window));
    let mut i = 0;
    while i < tree.nodes.len() {
        let n = &tree.nodes[i];
        let (dist, radius) = (x.distance(DVec3::from(n.center.map(f64::from))), f64::from(n.radius));
        if dist - radius >= reach {
            i = n.skip as usize;
        } else if radius < opening * dist.max(window) {
            visit(WalkItem::Node(i));
            i = n.skip as usize;
        } else if n.leaf {
            let members = &tree.order[n.first as usize..(n.first + n.count) as usize];
            members.iter().for_each(|&s| visit(WalkItem::Sample(s as usize)));
            i = n.skip as usize;
        } else {
            i += 1;
        }
    }
}

/// One vertex's [`receiver_walks`].
pub struct ReceiverWalk {
    /// The density correction's denominator per channel, `sum_i A_i T(rho_i, 1, 1)`.
    pub norm: [f32; 3],
    /// The walk's items within reach: `NODE_ITEM | n` for node `n`'s stand-in, `e` for the
    /// sample at leaf-order entry `e` (both relative to the object's).
    pub items: Vec<u32>,
}

/// Per vertex of object `o`, what stage 1 knows of it before any frame: the density
/// correction's denominator `sum_i A_i T(rho_i, 1, 1)` per channel over the walk the pass takes
/// ([`walk`]; a node at its members' area-weighted centroid), and that walk's items, a node as
/// `NODE_ITEM | n` and a sample as its leaf-order entry `e` (both relative to the object's). The
/// denominator depends on the geometry alone, so it is summed here once (f64), and the pass sums
/// only the lit terms; the walk too depends on the geometry alone, so the pass may read it
/// rather than take it again each frame.
///
/// The items are kept while the object's total stays within `max_items`; past it every list
/// comes back empty (so a mesh too large for the budget costs no host memory for them) and the
/// flag is false.
pub fn receiver_walks(
    o: &PreparedObject,
    tree: &SampleTree,
    beams: &ObjectBeams,
    tables: &[Option<BeamTable>; 3],
    max_items: usize,
) -> (Vec<ReceiverWalk>, bool) {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let kept = AtomicUsize::new(0);
    let at = |s: u32| (o.samples[s as usize].area, o.samples[s as usize].position.as_dvec3());
    let nodes: Vec<(f64, DVec3)> = tree
        .nodes
        .iter()
        .map(|n| {
            let members = tree.order[n.first as usize..(n.first + n.count) as usize].iter().map(|&s| at(s));
            let (area, moment) = members.fold((0.0, DVec3::ZERO), |(a, m), (da, p)| (a + da, m + da * p));
            (area, if area > 0.0 { moment / area } else { DVec3::from(n.center.map(f64::from)) })
        })
        .collect();
    let mut entry = vec![0u32; o.samples.len()];
    tree.order.iter().enumerate().for_each(|(e, &s)| entry[s as usize] = e as u32);
    let walks: Vec<ReceiverWalk> = o
        .mesh
        .positions()
        .par_iter()
        .map(|x| {
            let x = x.as_dvec3();
            let (mut norm, mut items) = ([0.0f64; 3], Vec::new());
            let keep = kept.load(Ordering::Relaxed) <= max_items;
            walk(tree, x, beams, |item| {
                let (area, p) = match item {
                    WalkItem::Node(n) => nodes[n],
                    WalkItem::Sample(s) => at(s as u32),
                };
                let dist = x.distance(p);
                if dist >= f64::from(beams.reach) {
                    return;
                }
                if keep {
                    items.push(match item {
                        WalkItem::Node(n) => crate::sampling::NODE_ITEM | n as u32,
                        WalkItem::Sample(s) => entry[s],
                    });
                }
                for (c, table) in tables.iter().enumerate() {
                    if let Some(t) = table {
                        norm[c] += area * t.lookup(dist * f64::from(beams.sigma_t[c]), 1.0, 1.0);
                    }
                }
            });
            kept.fetch_add(items.len(), Ordering::Relaxed);
            ReceiverWalk { norm: norm.map(|v| v as f32), items }
        })
        .collect();
    if kept.load(Ordering::Relaxed) <= max_items {
        (walks, true)
    } else {
        (walks.into_iter().map(|w| ReceiverWalk { items: Vec::new(), ..w }).collect(), false)
    }
}

/// Cells of one channel's block in a packed table (`glsl/common/beam_table.glsl`).
const CELLS: usize = (beam_table::NX - 1) * (beam_table::NY - 1) * (beam_table::NZ - 1);

/// What the scene's objects with a between-points channel give the pass.
pub struct PackedBeams {
    /// Every object's tables one after another as `glsl/common/beam_table.glsl` reads them (at
    /// least one entry, so the buffer binds).
    pub tables: Vec<[u32; 4]>,
    /// Per vertex of every object, objects one after another as in `GpuScene::vertices`, its
    /// [`receiver_walks`] denominator and first item (0 and an empty list on objects without
    /// the model), then one record closing the last list.
    pub receivers: Vec<BeamReceiverRecord>,
    /// The walks' items, vertex after vertex (at least one entry, so the buffer binds).
    pub items: Vec<u32>,
    /// Per object, its `ObjectBeams`.
    pub beams: Vec<Option<ObjectBeams>>,
}

/// [`PackedBeams`] of `scene`, with `trees[i]` object `i`'s sample hierarchy where the scene's
/// packing already built it (built here otherwise).
pub fn pack_tables(scene: &PreparedScene, trees: &[Option<SampleTree>]) -> PackedBeams {
    let mut out = PackedBeams { tables: vec![[0u32; 4]], receivers: Vec::new(), items: Vec::new(), beams: Vec::new() };
    let record = |norm: [f32; 3], first: usize| BeamReceiverRecord { norm, first_item: first as u32 };
    let budget = scene.scene.file.render.beam_walk_mib as usize * (1 << 20);
    for (i, o) in scene.objects.iter().enumerate() {
        let mut object = object_tables(o, out.tables.len(), scene.scene.file.render.beam_opening);
        match &mut object {
            Some((b, tables)) => {
                out.tables.extend(pack_object(tables));
                let built;
                let tree = match trees.get(i) {
                    Some(Some(tree)) => tree,
                    _ => {
                        built = o.sample_tree();
                        &built
                    }
                };
                let room = (budget / std::mem::size_of::<u32>()).saturating_sub(out.items.len());
                let (walks, kept) = receiver_walks(o, tree, b, tables, room);
                b.lists = kept;
                for w in walks {
                    out.receivers.push(record(w.norm, out.items.len()));
                    out.items.extend(w.items);
                }
            }
            None => {
                let first = out.items.len();
                out.receivers.extend(std::iter::repeat_n(record([0.0; 3], first), o.mesh.positions().len()));
            }
        }
        out.beams.push(object.map(|(b, _)| b));
    }
    out.receivers.push(record([0.0; 3], out.items.len()));
    if out.items.is_empty() {
        out.items.push(0);
    }
    out
}

/// One object's tables: per channel (zeros without the model) one entry per cell with its 8
/// corners as f16 pairs along x, at (y0, z0), (y1, z0), (y0, z1), (y1, z1).
fn pack_object(tables: &[Option<BeamTable>; 3]) -> Vec<[u32; 4]> {
    use beam_table::{NX, NY};
    let value = |c: usize, ix: usize, iy: usize, iz: usize| {
        tables[c].as_ref().map_or(0.0, |t| t.values[(iz * NY + iy) * NX + ix])
    };
    let pair = |c, ix, iy, iz| {
        let half = |v: f32| u32::from(half::f16::from_f32(v).to_bits());
        half(value(c, ix, iy, iz)) | half(value(c, ix + 1, iy, iz)) << 16
    };
    let mut out = Vec::with_capacity(3 * CELLS);
    for c in 0..3 {
        for k in 0..CELLS {
            let (ix, iy, iz) = (k % (NX - 1), (k / (NX - 1)) % (NY - 1), k / ((NX - 1) * (NY - 1)));
            out.push([
                pair(c, ix, iy, iz),
                pair(c, ix, iy + 1, iz),
                pair(c, ix, iy, iz + 1),
                pair(c, ix, iy + 1, iz + 1),
            ]);
        }
    }
    out
}


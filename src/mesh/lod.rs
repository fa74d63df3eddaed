//! Levels of detail: simplified versions of a mesh (meshoptimizer's edge-collapse simplifier,
//! Garland and Heckbert's quadric error, through the `meshopt` crate) that keep the original
//! vertices. Every level's triangles index the mesh's own vertex list, and each level is
//! simplified from the one before, so a coarser level's vertices are a subset of every finer
//! one's. A renderer can therefore switch levels without moving a vertex or re-deriving any
//! per-vertex value (normals, gathered exitance): the values at the vertices a level keeps are
//! exactly those of the full mesh.

use super::Mesh;

/// A level stops the chain when it keeps more than this share of the level before's triangles:
/// the simplifier has stalled (borders locked, or nothing left to collapse within its error).
const STALLED_SHARE: f64 = 0.8;

/// No level has fewer triangles than this: below it a mesh's silhouette visibly breaks while
/// drawing it costs next to nothing anyway.
pub const MIN_LEVEL_TRIANGLES: usize = 256;

/// The simplifier's error bound per step, relative to the mesh's extent: loose, so that the
/// triangle target (half the level before) decides each level; the error it reaches is kept.
const STEP_ERROR: f32 = 0.05;

/// One level of detail of a mesh.
#[derive(Clone, Debug)]
pub struct LodLevel {
    /// Its triangles, as indices into the mesh's vertices.
    pub triangles: Vec<[u32; 3]>,
    /// The vertices its triangles use, ascending.
    pub vertices: Vec<u32>,
    /// Mean edge length, scene units.
    pub mean_edge: f64,
    /// Bound on its distance from the full mesh, scene units: the simplifier's error of each
    /// step from the level before, summed (0 for the full mesh).
    pub error: f64,
    /// Simplified around locked vertices (`Mesh::levels_of_detail_locked`): where the caller's
    /// per-vertex values vary, its vertices are all kept, so its triangles' size says nothing
    /// of how well it carries them.
    pub locked: bool,
}

impl LodLevel {
    /// The bounding box (min, max) of its vertices, among the mesh's `positions`.
    pub fn bounds(&self, positions: &[glam::Vec3]) -> (glam::Vec3, glam::Vec3) {
        let (lo, hi) = (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY);
        self.vertices
            .iter()
            .fold((lo, hi), |(lo, hi), &v| (lo.min(positions[v as usize]), hi.max(positions[v as usize])))
    }
}

impl Mesh {
    /// The mesh's levels of detail, finest first: level 0 is the mesh itself, each next level
    /// has about half the triangles of the one before, down to [`MIN_LEVEL_TRIANGLES`] or until
    /// the simplifier stalls. Open borders are locked, so an open mesh keeps its outline (and
    /// its boundary vertices their distances to it).
    pub fn levels_of_detail(&self) -> Vec<LodLevel> {
        self.levels_of_detail_locked(&[])
    }

    /// [`Mesh::levels_of_detail`] keeping the vertices `locked` marks (one flag per vertex, or
    /// none): a caller whose per-vertex values vary where the geometry does not (sky light
    /// and its soft shadows across a flat floor) locks the vertices where they vary, and the
    /// simplifier removes only the others. The levels' errors stay geometric.
    pub fn levels_of_detail_locked(&self, locked: &[bool]) -> Vec<LodLevel> {
        assert!(locked.is_empty() || locked.len() == self.positions().len(), "one lock flag per vertex");
        let positions = self.positions();
        let bytes: &[u8] = bytemuck::cast_slice(positions);
        let adapter = meshopt::VertexDataAdapter::new(bytes, std::mem::size_of::<glam::Vec3>(), 0)
            .expect("Vec3 positions are 12-byte records");
        let scale = meshopt::simplify_scale(&adapter) as f64;
        let mut levels = vec![self.full_level()];
        loop {
            let last = levels.last().expect("level 0");
            let count = last.triangles.len();
            if count / 2 < MIN_LEVEL_TRIANGLES {
                break;
            }
            let indices: &[u32] = bytemuck::cast_slice(&last.triangles);
            let mut step_error = 0.0f32;
            let (target, options) = (3 * (count / 2), meshopt::SimplifyOptions::LockBorder);
            let simplified = if locked.is_empty() {
                meshopt::simplify(indices, &adapter, target, STEP_ERROR, options, Some(&mut step_error))
            } else {
                // No attributes: only the locks differ from the plain simplifier.
                meshopt::simplify_with_attributes_and_locks(
                    indices,
                    &adapter,
                    &[],
                    &[],
                    0,
                    locked,
                    target,
                    STEP_ERROR,
                    options,
                    Some(&mut step_error),
                )
            };
            let triangles: Vec<[u32; 3]> = bytemuck::cast_slice(&simplified).to_vec();
            if triangles.len() as f64 > STALLED_SHARE * count as f64 || triangles.len() < MIN_LEVEL_TRIANGLES / 2 {
                break;
            }
            let error = last.error + step_error as f64 * scale;
            let mut level = self.level(triangles, error);
            level.locked = !locked.is_empty();
            levels.push(level);
        }
        levels
    }

    /// Lock flags for [`Mesh::levels_of_detail_locked`]: the vertices where per-vertex `values`
    /// (RGB) differ from a neighbour's by more than `share` of their largest component over the
    /// mesh, in any channel. Both ends of such an edge are locked.
    pub fn locks_where_varying(&self, values: &[[f32; 3]], share: f32) -> Vec<bool> {
        assert_eq!(values.len(), self.positions().len(), "one value per vertex");
        let peak = values.iter().flatten().fold(0.0f32, |a, &b| a.max(b.abs()));
        let limit = share * peak;
        (0..values.len())
            .map(|v| {
                self.vertex_neighbours(v)
                    .iter()
                    .any(|&n| (0..3).any(|c| (values[v][c] - values[n as usize][c]).abs() > limit))
            })
            .collect()
    }

    /// The mesh itself as a level (level 0), for objects drawn whole.
    pub fn full_level(&self) -> LodLevel {
        self.level(self.triangles().to_vec(), 0.0)
    }

    fn level(&self, triangles: Vec<[u32; 3]>, error: f64) -> LodLevel {
        let positions = self.positions();
        let mut used = vec![false; positions.len()];
        let mut edges = 0.0;
        for t in &triangles {
            for k in 0..3 {
                used[t[k] as usize] = true;
                edges += positions[t[k] as usize].distance(positions[t[(k + 1) % 3] as usize]) as f64;
            }
        }
        let vertices = (0..positions.len() as u32).filter(|&v| used[v as usize]).collect();
        let mean_edge = edges / (3 * triangles.len()).max(1) as f64;
        LodLevel { triangles, vertices, mean_edge, error, locked: false }
    }
}

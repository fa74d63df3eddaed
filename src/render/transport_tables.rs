//! The transport kernels' data on the GPU (`glsl/transport.comp`, `optics::transport`): per
//! level of detail of each object with a kernel attached, its patches' lists, the kernel's
//! matrix (shared by the levels), and per vertex its patch neighbours, packed once at upload.

use super::ranges::LevelRange;
use crate::optics::transport::TransportKernel;
use crate::scene::build::{PreparedObject, PreparedScene};

/// One patch at one level of detail as glsl/transport.comp reads it (`TransportPatchRecord`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TransportPatchRecord {
    /// x: its first entry in the items; y: its vertices at this level (entries from x); z: its
    /// samples (entries after them); w: its rows' first entry in the matrix.
    pub items: [u32; 4],
    /// x: its area; y: the kernel's `mu_bar` (`TransportKernel::mu_mean`); z, w: 0.
    pub area: [f32; 4],
    /// xyz: its centre; w: 0.
    pub centre: [f32; 4],
    /// xyz: its unit mean normal (0 where its normals cancel); w: 0.
    pub normal: [f32; 4],
    /// x: its first entry-row entry in the matrix; y: their count (`TransportKernel::near`);
    /// z, w: 0.
    pub near: [u32; 4],
    /// xyz: the entries' mean (`Patches::entry_centres`); w: 0.
    pub entry: [f32; 4],
}

// glsl/receiver_view.comp reads the records as `PATCH_UVEC4S` = 6 uvec4s each: change both.
const _: () = assert!(std::mem::size_of::<TransportPatchRecord>() == 6 * 16);

/// Where one level of detail of an object's kernel lies in the packed buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelTransport {
    /// Its first patch record (absolute) and the patch count.
    pub patches: [u32; 2],
    /// The object's first vertex (absolute) and the level's vertex count.
    pub vertices: [u32; 2],
    /// The object's first vertex's neighbour entry (`uvec4`s, four per vertex).
    pub first_neighbour: u32,
    /// The level's first entry in `level_vertices`.
    pub first_entry: u32,
    /// Bit `c` set where the kernel scales channel `c`: those that take no single scattering
    /// between points (`PreparedObject::single_channels`), which the between-points pass wrote.
    pub channels: u32,
}

/// Every kernel packed (`pack`).
#[derive(Default)]
pub struct PackedTransport {
    /// Per patch of every kernel at every level.
    pub patches: Vec<TransportPatchRecord>,
    /// Per patch record, its level's vertices then its samples: (absolute index, area bits).
    pub items: Vec<[u32; 2]>,
    /// Each kernel's `W0` row by row (`[I K + J]`), RGB and 0; `Wx` alike; then per patch `I` its entry
    /// rows within the reach, two entries per `J`: `Wmu_IJ` RGB with `J` (exact as an f32),
    /// `Wt_IJ` RGB and 0.
    pub matrix: Vec<[f32; 4]>,
    /// Per vertex of every kernel's object, four `uvec4`s: eight (patch, weight bits) pairs,
    /// the patches relative to a level's first record.
    pub neighbours: Vec<[u32; 4]>,
    /// Per object in scene order, per level of detail, where its kernel lies.
    pub objects: Vec<Option<Vec<LevelTransport>>>,
}

/// Every attached kernel of `scene` packed; `first` gives each object's first vertex and
/// first sample (absolute), `levels` its levels' ranges.
pub fn pack(scene: &PreparedScene, first: &[[u32; 2]], levels: &[Vec<LevelRange>]) -> PackedTransport {
    let mut packed = PackedTransport::default();
    for ((o, &first), ranges) in scene.objects.iter().zip(first).zip(levels) {
        let placed = o.transport.as_ref().filter(|_| o.wants_transport()).map(|k| packed.object(o, k, first, ranges));
        packed.objects.push(placed);
    }
    packed
}

impl PackedTransport {
    fn object(
        &mut self,
        o: &PreparedObject,
        kernel: &TransportKernel,
        [first_vertex, first_sample]: [u32; 2],
        ranges: &[LevelRange],
    ) -> Vec<LevelTransport> {
        let placed = kernel.placed(&o.mesh);
        let k = placed.len();
        let single = o.single_channels();
        let channels = (0..3).filter(|&c| !single[c]).map(|c| 1u32 << c).sum();
        let mut samples = vec![Vec::new(); k];
        for (s, sample) in o.samples.iter().enumerate() {
            let i = kernel.sample_patch(&o.mesh, sample.triangle, sample.barycentric);
            samples[i as usize].push([first_sample + s as u32, (sample.area as f32).to_bits()]);
        }
        let first_row = self.matrix.len() as u32;
        for row in [&kernel.flux, &kernel.shift] {
            self.matrix
                .extend((0..k * k).map(|ij| [0, 1, 2].map(|c| row[c][ij] as f32)).map(|[r, g, b]| [r, g, b, 0.0]));
        }
        let entry = placed.entry_centres(&o.mesh);
        let mut near_rows = Vec::with_capacity(k);
        for (i, near) in kernel.near().iter().enumerate() {
            near_rows.push([self.matrix.len() as u32, near.len() as u32]);
            for &j in near {
                let at = i * k + j as usize;
                let (mu, t) =
                    ([0, 1, 2].map(|c| kernel.depth[c][at] as f32), [0, 1, 2].map(|c| kernel.sideways[c][at] as f32));
                self.matrix.push([mu[0], mu[1], mu[2], j as f32]);
                self.matrix.push([t[0], t[1], t[2], 0.0]);
            }
        }
        let first_neighbour = self.neighbours.len() as u32;
        for near in TransportKernel::vertex_neighbours(&placed, &o.mesh) {
            let mut pairs = [[0u32; 2]; crate::mesh::patches::NEIGHBOURS];
            for (slot, &(i, w)) in pairs.iter_mut().zip(&near) {
                *slot = [i, (w as f32).to_bits()];
            }
            self.neighbours.extend(pairs.chunks(2).map(|c| [c[0][0], c[0][1], c[1][0], c[1][1]]));
        }
        o.levels
            .iter()
            .zip(ranges)
            .map(|(level, range)| {
                let first_patch = self.patches.len() as u32;
                let cells = level_cells(o, &level.triangles);
                let mut vertices = vec![Vec::new(); k];
                for &v in &level.vertices {
                    let area = (cells[v as usize] as f32).to_bits();
                    vertices[kernel.patches.of_vertex[v as usize] as usize].push([first_vertex + v, area]);
                }
                for i in 0..k {
                    let first_item = self.items.len() as u32;
                    self.items.extend(&vertices[i]);
                    self.items.extend(&samples[i]);
                    let (nv, ns) = (vertices[i].len() as u32, samples[i].len() as u32);
                    let row = first_row + (i * k) as u32;
                    let (c, n) = (placed.centre(i), placed.normal(i));
                    self.patches.push(TransportPatchRecord {
                        items: [first_item, nv, ns, row],
                        area: [placed.area[i] as f32, kernel.mu_mean as f32, 0.0, 0.0],
                        centre: [c.x as f32, c.y as f32, c.z as f32, 0.0],
                        normal: [n.x as f32, n.y as f32, n.z as f32, 0.0],
                        near: [near_rows[i][0], near_rows[i][1], 0, 0],
                        entry: [entry[i].x as f32, entry[i].y as f32, entry[i].z as f32, 0.0],
                    });
                }
                LevelTransport {
                    patches: [first_patch, k as u32],
                    vertices: [first_vertex, range.vertex_count],
                    first_neighbour,
                    first_entry: range.first_entry,
                    channels,
                }
            })
            .collect()
    }
}

/// Per vertex of object `o`, its dual cell in `triangles` (a level of detail's): a third of
/// each of its triangles there.
pub fn level_cells(o: &PreparedObject, triangles: &[[u32; 3]]) -> Vec<f64> {
    let p = o.mesh.positions();
    let mut cells = vec![0.0; p.len()];
    for t in triangles {
        let [a, b, c] = t.map(|v| p[v as usize].as_dvec3());
        let third = 0.5 * (b - a).cross(c - a).length() / 3.0;
        t.iter().for_each(|&v| cells[v as usize] += third);
    }
    cells
}

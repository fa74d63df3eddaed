//! The transport kernels' data on the GPU (`glsl/transport.comp`, `optics::transport`): per
//! patch its lists and area, the kernels' matrices, and per vertex its patch neighbours, packed
//! once at upload for every object that has a kernel attached.

use crate::optics::transport::TransportKernel;
use crate::scene::build::{PreparedObject, PreparedScene};

/// One patch as glsl/transport.comp reads it (`TransportPatchRecord`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TransportPatchRecord {
    /// x: its first entry in the items; y: its vertices (entries from x); z: its samples
    /// (entries after them); w: its row's first entry in the matrix.
    pub items: [u32; 4],
    /// x: its area; y, z, w: 0.
    pub area: [f32; 4],
}

/// Where one object's kernel lies in the packed buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectTransport {
    /// Its first patch (absolute) and its patch count.
    pub patches: [u32; 2],
    /// Its first vertex (absolute) and its vertex count.
    pub vertices: [u32; 2],
    /// Its first vertex's neighbour entry (`uvec4`s, four per vertex).
    pub first_neighbour: u32,
}

/// Every kernel packed (`pack`).
#[derive(Default)]
pub struct PackedTransport {
    /// Per patch of every kernel.
    pub patches: Vec<TransportPatchRecord>,
    /// Per patch, its vertices then its samples: (absolute index, area as f32 bits).
    pub items: Vec<[u32; 2]>,
    /// Each kernel's `W` row by row, RGB and 0.
    pub matrix: Vec<[f32; 4]>,
    /// Per vertex of every kernel's object, four `uvec4`s: eight (patch, weight bits) pairs.
    pub neighbours: Vec<[u32; 4]>,
    /// Per object in scene order, where its kernel lies.
    pub objects: Vec<Option<ObjectTransport>>,
}

/// Every attached kernel of `scene` packed; `first` gives each object's first vertex and
/// first sample (absolute).
pub fn pack(scene: &PreparedScene, first: &[[u32; 2]]) -> PackedTransport {
    let mut packed = PackedTransport::default();
    for (o, &first) in scene.objects.iter().zip(first) {
        let placed = o.transport.as_ref().filter(|_| o.wants_transport()).map(|k| packed.object(o, k, first));
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
    ) -> ObjectTransport {
        let p = &kernel.placed(&o.mesh);
        let (first_patch, k) = (self.patches.len() as u32, p.len());
        let (mut vertices, mut samples) = (vec![Vec::new(); k], vec![Vec::new(); k]);
        for (v, &i) in p.of_vertex.iter().enumerate() {
            vertices[i as usize].push([first_vertex + v as u32, (p.cells[v] as f32).to_bits()]);
        }
        for (s, sample) in o.samples.iter().enumerate() {
            let i = kernel.sample_patch(&o.mesh, sample.triangle, sample.barycentric);
            samples[i as usize].push([first_sample + s as u32, (sample.area as f32).to_bits()]);
        }
        let first_row = self.matrix.len() as u32;
        for i in 0..k {
            let first_item = self.items.len() as u32;
            self.items.extend(&vertices[i]);
            self.items.extend(&samples[i]);
            self.patches.push(TransportPatchRecord {
                items: [first_item, vertices[i].len() as u32, samples[i].len() as u32, first_row + (i * k) as u32],
                area: [p.area[i] as f32, 0.0, 0.0, 0.0],
            });
        }
        self.matrix.extend((0..k * k).map(|ij| [0, 1, 2].map(|c| kernel.flux[c][ij] as f32)).map(|[r, g, b]| [r, g, b, 0.0]));
        let first_neighbour = self.neighbours.len() as u32;
        for near in TransportKernel::vertex_neighbours(p, &o.mesh) {
            let mut pairs = [[0u32; 2]; crate::mesh::patches::NEIGHBOURS];
            for (slot, &(i, w)) in pairs.iter_mut().zip(&near) {
                *slot = [first_patch + i, (w as f32).to_bits()];
            }
            self.neighbours.extend(pairs.chunks(2).map(|c| [c[0][0], c[0][1], c[1][0], c[1][1]]));
        }
        ObjectTransport {
            patches: [first_patch, k as u32],
            vertices: [first_vertex, o.mesh.positions().len() as u32],
            first_neighbour,
        }
    }
}

//! Where each object lies in the scene's shared GPU buffers: its levels of detail and their
//! draws, its receivers, its texture atlas, and its vertex and sample ranges (what
//! `GpuScene` hands the passes to dispatch and draw with).

use crate::mesh::Enclosure;
use glam::Vec3;

/// One level of detail of an object (`mesh::LodLevel`): its draw, and its vertices (the
/// gather's receivers at that level) as a range of `GpuScene::level_vertices`.
#[derive(Clone, Copy, Debug)]
pub struct LevelRange {
    /// Its triangles in the shared index buffer.
    pub draw: DrawRange,
    /// First entry of its vertex list in `level_vertices`.
    pub first_entry: u32,
    /// Vertices it uses (0 for an opaque object, which is never gathered).
    pub vertex_count: u32,
    /// Whether its triangles enclose a volume, and which way they face (the shading pass culls
    /// the faces hidden inside, `shade::hidden_faces`).
    pub enclosure: Enclosure,
    /// Its vertices' bounding box, scene units: (min, max).
    pub bounds: (Vec3, Vec3),
    /// Its longest edge (`mesh::facing::longest_edge`): a vertex of a triangle that meets the
    /// view frustum lies at most this far outside it.
    pub reach: f32,
}

/// A draw of one object: index range and vertex offset in the shared buffers.
#[derive(Clone, Copy, Debug)]
pub struct DrawRange {
    /// First index of the object's triangles in the shared index buffer.
    pub first_index: u32,
    /// Number of indices, three per triangle.
    pub index_count: u32,
    /// Added to every index: the object's first vertex in the shared vertex buffer.
    pub vertex_offset: i32,
}

/// A translucent object as the gathers see it.
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    /// Index of the object (its `ObjectRecord`).
    pub object: u32,
    /// Its vertex count: the threads of the vertex gather and of the sparse gather's stage 1.
    pub vertex_count: u32,
    /// Its sample count: the threads of the sparse gather's stage 0.
    pub sample_count: u32,
    /// Its root node in `GpuScene::tree_nodes`.
    pub first_node: u32,
    /// Its node count: the threads of the hierarchical gather's stage 0.
    pub node_count: u32,
    /// Its first entry in `GpuScene::receiver_order` (its vertices in group order).
    pub first_receiver: u32,
    /// Its first group in `GpuScene::receiver_groups`.
    pub first_group: u32,
}

/// Where one object's atlas and sum tree lie, for the texture gather (all zero for an object
/// without an atlas).
#[derive(Clone, Copy, Debug, Default)]
pub struct TextureRange {
    /// The depth of its sum tree (`mesh::atlas::tree_levels` of its texels).
    pub levels: u32,
    /// Its root in `GpuScene::texture_pyramid`.
    pub first_node: u32,
    /// Its index map's first entry in `GpuScene::texel_index`.
    pub first_index: u32,
    /// Its atlas's texels per side.
    pub resolution: u32,
    /// Its local window's half-width in texels (`PreparedObject::window_radius`).
    pub radius: u32,
}

/// Where one object's vertices and samples lie in the shared buffers (every object, opaque ones
/// included): what per-object dispatches cover.
#[derive(Clone, Copy, Debug)]
pub struct ObjectRange {
    /// First vertex in the shared vertex buffer.
    pub first_vertex: u32,
    /// Its vertex count.
    pub vertex_count: u32,
    /// First sample in the shared sample buffer.
    pub first_sample: u32,
    /// Its sample count (0 for an opaque object).
    pub sample_count: u32,
    /// Index of refraction of a translucent object; 0 for an opaque one.
    pub eta: f32,
}

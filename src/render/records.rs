//! `#[repr(C)]` mirrors of the std430 records in `glsl/common/scene.glsl`, and the vertex layout
//! every raster pass reads. Only 4-byte scalars and 16-byte vectors, so std430 and repr(C) agree;
//! `tests/render_records.rs` pins sizes and offsets.

use ash::vk;

pub const MATERIAL_OPAQUE: f32 = 0.0;
pub const MATERIAL_TRANSLUCENT: f32 = 1.0;

/// `ObjectRecord` in glsl/common/scene.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ObjectRecord {
    pub albedo_roughness: [f32; 4],
    pub eta_norm_kind: [f32; 4],
    /// Per channel: alpha', sigma_tr, z_r, z_v, with lengths in scene units.
    pub dipole: [[f32; 4]; 3],
    /// First vertex, vertex count, first sample, sample count.
    pub ranges: [u32; 4],
}

/// `SampleRecord` in glsl/common/scene.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleRecord {
    pub position_area: [f32; 4],
    pub normal_object: [f32; 4],
}

/// One mesh vertex as the raster passes read it (binding 0). Exitance is a second vertex
/// buffer (binding 1, `[f32; 4]` per vertex) written by the gather pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
}

impl Vertex {
    pub fn binding() -> vk::VertexInputBindingDescription {
        vk::VertexInputBindingDescription {
            binding: 0,
            stride: std::mem::size_of::<Vertex>() as u32,
            input_rate: vk::VertexInputRate::VERTEX,
        }
    }
    pub fn position_attribute() -> vk::VertexInputAttributeDescription {
        vk::VertexInputAttributeDescription { location: 0, binding: 0, format: vk::Format::R32G32B32_SFLOAT, offset: 0 }
    }
    pub fn normal_attribute() -> vk::VertexInputAttributeDescription {
        vk::VertexInputAttributeDescription {
            location: 1,
            binding: 0,
            format: vk::Format::R32G32B32_SFLOAT,
            offset: 12,
        }
    }
}

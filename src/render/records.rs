//! The GPU's view of a prepared scene: `#[repr(C)]` mirrors of the std430 records in
//! `glsl/common/scene.glsl` and `glsl/common/lights.glsl`, and the vertex layout every raster pass
//! reads. Every record is packed here, and only here, from the typed scene values. Only 4-byte
//! scalars and 16-byte vectors, so std430 and repr(C) agree; `tests/render_records.rs` pins sizes
//! and offsets against the GLSL declarations.

use crate::optics::fresnel;
use crate::optics::gpu::DipoleChannelGpu;
use crate::sampling::SamplePoint;
use crate::scene::build::{PreparedObject, ResolvedMaterial};
use crate::scene::lights::{LightKind, PreparedLight};
use ash::vk;

/// Kind of an opaque (Lambertian) object in `ObjectRecord::kind`; `MATERIAL_OPAQUE` in
/// glsl/common/scene.glsl.
pub const MATERIAL_OPAQUE: u32 = 0;
/// Kind of a translucent (dipole BSSRDF) object in `ObjectRecord::kind`;
/// `MATERIAL_TRANSLUCENT` in glsl/common/scene.glsl.
pub const MATERIAL_TRANSLUCENT: u32 = 1;

/// Kind of a directional light in `LightGpu::kind`; `LIGHT_DIRECTIONAL` in glsl/common/lights.glsl.
pub const LIGHT_DIRECTIONAL: u32 = 0;
/// Kind of a point light in `LightGpu::kind`; `LIGHT_POINT` in glsl/common/lights.glsl.
pub const LIGHT_POINT: u32 = 1;
/// Kind of a spot light in `LightGpu::kind`; `LIGHT_SPOT` in glsl/common/lights.glsl.
pub const LIGHT_SPOT: u32 = 2;

/// `ObjectRecord` in glsl/common/scene.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ObjectRecord {
    /// rgb: the diffuse albedo. Opaque: the Lambert albedo. Translucent: the total diffuse
    /// reflectance `R_d,total` per channel (`Dipole::r_d_total`), a constant of the material
    /// that shading multiplies locally computed channels by; taken here in f64 once rather
    /// than per pixel in f32 (it was a quarter of the shading pass on lavapipe). w: GGX
    /// roughness (both kinds).
    pub albedo_roughness: [f32; 4],
    /// Relative index of refraction eta (1.5 for opaque, for its specular lobe).
    pub eta: f32,
    /// The BSSRDF normalization 1 / (pi T(eta)) (0 for opaque).
    pub norm: f32,
    /// `MATERIAL_*`.
    pub kind: u32,
    /// The channels computed locally, bit c: channel c (set per frame from the plan,
    /// `GpuScene::set_local_channels`).
    pub local_channels: u32,
    /// Per channel: alpha', sigma_tr, z_r, z_v, with lengths in scene units.
    pub dipole: [DipoleChannelGpu; 3],
    /// First vertex, vertex count, first sample, sample count.
    pub ranges: [u32; 4],
    /// rgb: per channel, `1 / k^2` for the near-field blend's radius `k sqrt(dA)`
    /// (`PreparedObject::near_blend_radii`; the gathers divide by the area once and multiply
    /// per channel); w: 0.
    pub near_blend: [f32; 4],
}

impl ObjectRecord {
    /// `ranges`: first vertex, vertex count, first sample, sample count in the shared buffers.
    pub fn new(object: &PreparedObject, ranges: [u32; 4]) -> ObjectRecord {
        match &object.material {
            ResolvedMaterial::Translucent { material, dipoles, roughness, .. } => {
                let t_eta = fresnel::diffuse_transmittance(material.eta);
                ObjectRecord {
                    albedo_roughness: [
                        dipoles[0].r_d_total() as f32,
                        dipoles[1].r_d_total() as f32,
                        dipoles[2].r_d_total() as f32,
                        *roughness,
                    ],
                    eta: material.eta as f32,
                    // The BSSRDF's normalization 1 / (pi T(eta)) (optics::Dipole::s_d).
                    norm: (1.0 / (std::f64::consts::PI * t_eta)) as f32,
                    kind: MATERIAL_TRANSLUCENT,
                    local_channels: 0,
                    dipole: dipoles.each_ref().map(DipoleChannelGpu::from),
                    ranges,
                    near_blend: {
                        let k = object.near_blend_radii();
                        [(1.0 / (k[0] * k[0])) as f32, (1.0 / (k[1] * k[1])) as f32, (1.0 / (k[2] * k[2])) as f32, 0.0]
                    },
                }
            }
            ResolvedMaterial::Opaque { albedo, roughness } => ObjectRecord {
                albedo_roughness: [albedo[0], albedo[1], albedo[2], *roughness],
                eta: 1.5,
                norm: 0.0,
                kind: MATERIAL_OPAQUE,
                local_channels: 0,
                dipole: [DipoleChannelGpu::default(); 3],
                ranges,
                near_blend: [0.0; 4],
            },
        }
    }
}

/// `SampleRecord` in glsl/common/scene.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleRecord {
    /// xyz: world position; w: area weight (scene units^2).
    pub position_area: [f32; 4],
    /// Unit (interpolated) shading normal.
    pub normal: [f32; 3],
    /// The unit normal of the triangle the sample lies on, [`pack_octahedral`]: where it faces
    /// away from a light that the shading normal faces, the sample sits beside its mesh's
    /// terminator, and the splat's hybrid visibility asks a ray rather than the shadow map.
    pub face_normal: u32,
}

impl SampleRecord {
    /// Pack one sample point lying on a triangle of unit face normal `face_normal`.
    pub fn new(sample: &SamplePoint, face_normal: glam::Vec3) -> SampleRecord {
        let (p, n) = (sample.position, sample.normal);
        SampleRecord {
            position_area: [p.x, p.y, p.z, sample.area as f32],
            normal: n.to_array(),
            face_normal: pack_octahedral(face_normal),
        }
    }
}

/// A unit vector in 32 bits: its octahedral map (Cigolle et al. 2014, "A Survey of Efficient
/// Representations for Independent Unit Vectors") as two snorm16 values, x in the low half,
/// as GLSL's `unpackSnorm2x16` reads them (`unpack_octahedral` in glsl/common/scene.glsl).
pub fn pack_octahedral(n: glam::Vec3) -> u32 {
    let n = n / (n.x.abs() + n.y.abs() + n.z.abs()).max(f32::MIN_POSITIVE);
    let sign = |v: f32| if v >= 0.0 { 1.0 } else { -1.0 };
    let (x, y) = if n.z >= 0.0 { (n.x, n.y) } else { ((1.0 - n.y.abs()) * sign(n.x), (1.0 - n.x.abs()) * sign(n.y)) };
    let snorm = |v: f32| u32::from((v.clamp(-1.0, 1.0) * 32767.0).round() as i16 as u16);
    snorm(x) | snorm(y) << 16
}

/// `SplatRecord` in glsl/common/scene.glsl: what the splat pass writes for one sample.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SplatRecord {
    /// rgb: transmitted irradiance E_i; w: the sample's area.
    pub irradiance_area: [f32; 4],
    /// rgb: near-field energy per channel (`optics::kernel::near_energy`); w: the key lights'
    /// transmitted flux, summed over the channels.
    pub near_energy: [f32; 4],
    /// xyz: the direction light travels inside after refracting in, the key lights' directions
    /// weighted by their transmitted flux (unit; `-n` where no key light reaches); w: the
    /// length of that weighted sum. The between-points single scattering reads the direction
    /// (glsl/beam_gather.comp), the transport kernel's entry basis the sum
    /// (`optics::transport::SampleFlux::from_splat`).
    pub beam: [f32; 4],
}

impl SplatRecord {
    /// Pack one sample's splat output with no key light's direction (the w of `near_energy` and
    /// of `beam` 0: the transport kernel takes its light as entering diffusely).
    pub fn new(irradiance: [f32; 3], area: f32, near_energy: [f32; 3], beam: [f32; 3]) -> SplatRecord {
        let [e0, e1, e2] = irradiance;
        let [n0, n1, n2] = near_energy;
        let [b0, b1, b2] = beam;
        SplatRecord { irradiance_area: [e0, e1, e2, area], near_energy: [n0, n1, n2, 0.0], beam: [b0, b1, b2, 0.0] }
    }

    /// What the transport kernel's entry basis reads: the key lights' flux-weighted sum of
    /// refracted directions and their flux.
    pub fn key_entry(&self) -> ([f32; 3], f32) {
        let [x, y, z, w] = self.beam;
        ([x * w, y * w, z * w], self.near_energy[3])
    }
}

/// `TreeNodeRecord` in glsl/common/scene.glsl: one node of an object's sample hierarchy
/// (`sampling::SampleTree`), indices made absolute in the shared node and order buffers.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TreeNodeRecord {
    /// xyz: centre of the bounding sphere of the node's samples; w: its radius.
    pub center_radius: [f32; 4],
    /// x: total area of the samples; y: their largest near-blend radius; z: mean area; w: 0.
    pub area_reach: [f32; 4],
    /// x: first entry in the order buffer; y: sample count; z: the node after the subtree; w: 1
    /// for a leaf.
    pub range_skip: [u32; 4],
}

impl TreeNodeRecord {
    /// Pack `node`, offsetting its node and order indices by the object's first node and
    /// first order entry in the shared buffers.
    pub fn new(node: &crate::sampling::TreeNode, first_node: u32, first_entry: u32) -> TreeNodeRecord {
        let [x, y, z] = node.center;
        TreeNodeRecord {
            center_radius: [x, y, z, node.radius],
            area_reach: [node.area, node.reach, node.area / node.count.max(1) as f32, 0.0],
            range_skip: [first_entry + node.first, node.count, first_node + node.skip, node.leaf as u32],
        }
    }
}

/// `BeamNodeRecord` in glsl/common/scene.glsl: what stage 0 of the between-points single
/// scattering (glsl/beam_gather.comp) aggregates per node after each splat, so that a far node
/// stands in for its members.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BeamNodeRecord {
    /// rgb: `sum A_i E_i` per channel; w: `sum A_i`.
    pub power: [f32; 4],
    /// xyz: the members' area-weighted centroid; w: `sum P_i`, `P_i = A_i (E_r + E_g + E_b)`.
    pub position: [f32; 4],
    /// xyz: `sum A_i n_i`; w: 0.
    pub normal: [f32; 4],
    /// xyz: `sum P_i w_i` over the members' beams; w: 0.
    pub beam: [f32; 4],
}

/// `BeamSourceRecord` in glsl/common/scene.glsl: one sample as the between-points single
/// scattering reads it, written per leaf-order entry by its stage 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BeamSourceRecord {
    /// xyz: position; w: `mu`, the cosine of its beam with the inward normal.
    pub position_mu: [f32; 4],
    /// rgb: `A E` per channel; w: `A`.
    pub power_area: [f32; 4],
    /// xyz: unit normal; w: the beam's unit direction along the tangent plane,
    /// [`pack_octahedral`], as float bits.
    pub normal_along: [f32; 4],
}

/// `BeamReceiverRecord` in glsl/common/scene.glsl: per vertex, what the between-points single
/// scattering's stage 1 knows of it before any frame (`render::beam_gather::receiver_walks`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BeamReceiverRecord {
    /// The density correction's denominator per channel, `sum_i A_i T(rho_i, 1, 1)`.
    pub norm: [f32; 3],
    /// Its walk's first item in `GpuScene::beam_items`; the next vertex's is one past its last
    /// (a last record closes the list).
    pub first_item: u32,
}

/// `NodePowerRecord` in glsl/common/scene.glsl: what stage 0 of the hierarchical gather
/// aggregates per node after each splat.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct NodePowerRecord {
    /// rgb: transmitted power `sum E_i A_i` per channel; w: the members' mean area (the node's
    /// `TreeNodeRecord::area_reach` z), so that stage 1 reads one record per node item.
    pub power: [f32; 4],
    /// xyz: centroid of the samples weighted by their power summed over channels (the bounding
    /// centre when unlit); w: that total weight.
    pub mean_weight: [f32; 4],
    /// xyz: the members' power-weighted covariance about the centroid: xx, yy, zz; w: 0.
    pub cov_diag: [f32; 4],
    /// xyz: xy, xz, yz; w: 0.
    pub cov_off: [f32; 4],
}

/// `ReceiverGroupRecord` in glsl/common/scene.glsl: one group of receivers of the hierarchical
/// gather (`sampling::ReceiverGroups`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ReceiverGroupRecord {
    /// xyz: centre of a sphere holding the group's receivers; w: its radius.
    pub center_radius: [f32; 4],
    /// Hierarchical gather: x: first entry in the group items; y: how many of them are nodes
    /// (first); z: how many samples follow; w: 0.
    pub items: [u32; 4],
    /// Sparse gather: x: first entry in the blend items; y: their count; z, w: 0.
    pub blend: [u32; 4],
}

/// `struct Light` in glsl/common/lights.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightGpu {
    /// Position (point, spot).
    pub position: [f32; 3],
    /// `LIGHT_*`.
    pub kind: u32,
    /// xyz: unit vector towards the light (directional) or the spot axis pointing away from the
    /// light; w: cosine of the spot's outer angle.
    pub direction_cos: [f32; 4],
    /// rgb: irradiance in W/m^2 (directional) or intensity in W/sr (point, spot); w: shadow-map
    /// layer, negative when the light casts no shadow.
    pub power_layer: [f32; 4],
    /// x: cosine of the spot's inner angle; y: shadow-map texel size in uv; z: normal offset (world
    /// units) against self-shadowing; w: 1 for a direction of the environment light, else 0.
    pub spot_texel: [f32; 4],
    /// World -> the light's shadow clip space (depth 0..1), column-major.
    pub shadow_matrix: [[f32; 4]; 4],
}

impl LightGpu {
    /// Pack one prepared light.
    pub fn new(light: &PreparedLight) -> LightGpu {
        let ((position, kind), direction_cos, power, cos_inner) = match light.kind {
            LightKind::Directional { direction: d, irradiance } => {
                (([0.0; 3], LIGHT_DIRECTIONAL), [d.x, d.y, d.z, 0.0], irradiance, 0.0)
            }
            LightKind::Point { position: p, intensity } => ((p.to_array(), LIGHT_POINT), [0.0; 4], intensity, 0.0),
            LightKind::Spot { position: p, axis: a, intensity, cos_outer, cos_inner } => {
                ((p.to_array(), LIGHT_SPOT), [a.x, a.y, a.z, cos_outer], intensity, cos_inner)
            }
        };
        // A negative layer tells the shaders the light casts no shadow.
        let layer = light.shadow_layer.map_or(-1.0, |l| l as f32);
        LightGpu {
            position,
            kind,
            direction_cos,
            power_layer: [power.x, power.y, power.z, layer],
            spot_texel: [cos_inner, light.shadow_texel, light.normal_offset, if light.environment { 1.0 } else { 0.0 }],
            shadow_matrix: light.shadow_matrix.to_cols_array_2d(),
        }
    }
}

/// One mesh vertex as the raster passes read it (binding 0) and as `VertexRecord` in
/// glsl/common/scene.glsl for compute passes. Exitance is a second vertex buffer (binding 1,
/// `[f32; 4]` per vertex) written by the gather pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    /// World-space position (location 0).
    pub position: [f32; 3],
    /// World-space vertex normal (location 1).
    pub normal: [f32; 3],
}

impl Vertex {
    /// Vertex buffer binding 0: one `Vertex` per vertex, 24-byte stride.
    pub fn binding() -> vk::VertexInputBindingDescription {
        vk::VertexInputBindingDescription {
            binding: 0,
            stride: std::mem::size_of::<Vertex>() as u32,
            input_rate: vk::VertexInputRate::VERTEX,
        }
    }
    /// Location 0: `position`, three f32 at offset 0 of binding 0.
    pub fn position_attribute() -> vk::VertexInputAttributeDescription {
        vk::VertexInputAttributeDescription { location: 0, binding: 0, format: vk::Format::R32G32B32_SFLOAT, offset: 0 }
    }
    /// Location 1: `normal`, three f32 at offset 12 of binding 0.
    pub fn normal_attribute() -> vk::VertexInputAttributeDescription {
        vk::VertexInputAttributeDescription {
            location: 1,
            binding: 0,
            format: vk::Format::R32G32B32_SFLOAT,
            offset: 12,
        }
    }
}

/// `BvhNode` in glsl/common/rays.glsl: one node of the shadow casters' hierarchy
/// (`mesh::bvh::FlatNode`), its first and count stored as the bits of the w components.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhNodeRecord {
    /// xyz: the box's lower corner; w: the bits of a leaf's first triangle or an inner node's left
    /// child.
    pub min_first: [f32; 4],
    /// xyz: the box's upper corner; w: the bits of a leaf's triangle count (0: inner node).
    pub max_count: [f32; 4],
}

impl BvhNodeRecord {
    /// Pack one flat node.
    pub fn new(n: &crate::mesh::bvh::FlatNode) -> BvhNodeRecord {
        let [a, b, c] = n.min;
        let [d, e, f] = n.max;
        BvhNodeRecord { min_first: [a, b, c, f32::from_bits(n.first)], max_count: [d, e, f, f32::from_bits(n.count)] }
    }
}

/// `BvhTriangle` in glsl/common/rays.glsl: a caster triangle's corners (w unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhTriangleRecord {
    /// The corners, xyz each.
    pub corners: [[f32; 4]; 3],
}

impl BvhTriangleRecord {
    /// Pack one triangle.
    pub fn new(t: &[[f32; 3]; 3]) -> BvhTriangleRecord {
        BvhTriangleRecord { corners: t.map(|[x, y, z]| [x, y, z, 0.0]) }
    }
}

#[cfg(test)]
mod tests {
    use super::pack_octahedral;
    use glam::Vec3;

    /// `unpack_octahedral` of glsl/common/scene.glsl, line for line.
    fn unpack(bits: u32) -> Vec3 {
        let snorm = |h: u32| (f32::from(h as u16 as i16) / 32767.0).clamp(-1.0, 1.0);
        let (x, y) = (snorm(bits & 0xffff), snorm(bits >> 16));
        let mut v = Vec3::new(x, y, 1.0 - x.abs() - y.abs());
        if v.z < 0.0 {
            let sign = |a: f32| if a >= 0.0 { 1.0 } else { -1.0 };
            (v.x, v.y) = ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y));
        }
        v.normalize()
    }

    #[test]
    fn octahedral_packing_keeps_a_unit_vector_within_1e_4() {
        let mut worst = 0.0f32;
        for i in 0..2000 {
            // A spiral over the sphere, poles and the equator's axes included.
            let z = 1.0 - 2.0 * i as f32 / 1999.0;
            let phi = i as f32 * 2.399_963;
            let r = (1.0 - z * z).max(0.0).sqrt();
            for n in [Vec3::new(r * phi.cos(), r * phi.sin(), z), Vec3::X, Vec3::NEG_Y, Vec3::NEG_Z] {
                worst = worst.max((unpack(pack_octahedral(n)) - n).length());
            }
        }
        assert!(worst < 1e-4, "worst error {worst}");
    }
}

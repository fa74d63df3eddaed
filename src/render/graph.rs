//! The frame's resources by name, and what each pass declares it reads and writes. A small
//! render graph for a fixed set of passes, after kajiya-rg's `.read()` / `.write()` handles but
//! simpler: the passes run in the plan's order, each says which named `Resource`s it touches and
//! how (`RenderPass::uses`), and the pass loop records the barriers that follow from that
//! (`gpu::Hazards`), across frames too. A pass never names who reads its output, so a new
//! reader needs no edit to its producer.
//!
//! The same names bind descriptor sets: `Resources::bind` gives each resource with its GLSL
//! block or variable name, and pipeline creation checks it against the name the shader
//! declares at that binding (`gpu::GpuError::BindingMismatch`).

use super::gpu_scene::GpuScene;
use super::targets::FrameTargets;
use crate::gpu::{Access, Binding, Buffer, GpuError, GpuResult, Named};

/// A resource of the frame: the scene's buffers (`GpuScene`), the frame targets
/// (`FrameTargets`), and the few that a pass owns. Each is one GLSL block or image name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Resource {
    /// `VertexRecord` per vertex (`GpuScene::vertices`); also the vertex stream of the draws.
    Vertices,
    /// `ObjectRecord` per object (`GpuScene::objects`), rewritten by uploads.
    Objects,
    /// `Light` per prepared light (`GpuScene::lights`), rewritten by uploads.
    Lights,
    /// `SampleRecord` per sample (`GpuScene::samples`).
    Samples,
    /// `SplatRecord` per sample, the splat's output (`GpuScene::splat`).
    Splat,
    /// The environment's transmitted irradiance per sample, kept by the splat between frames
    /// (`GpuScene::splat_environment`).
    SplatEnvironment,
    /// Exitance per vertex, the vertex-wide gathers' output (`GpuScene::exitance`); also a
    /// vertex stream of shading.
    Exitance,
    /// Environment irradiance per vertex (`GpuScene::environment_irradiance`); also a vertex
    /// stream of shading.
    EnvironmentIrradiance,
    /// The locally computed channels' exitance per vertex (`GpuScene::local_exitance`).
    LocalExitance,
    /// Distances to open boundaries per vertex (`GpuScene::vertex_boundary`).
    VertexBoundary,
    /// The sample hierarchies' nodes (`GpuScene::tree_nodes`).
    TreeNodes,
    /// The hierarchies' leaf order (`GpuScene::tree_order`).
    TreeOrder,
    /// Power per node, the hierarchical gather's stage 0 (`GpuScene::node_power`).
    NodePower,
    /// Vertices in receiver-group order (`GpuScene::receiver_order`).
    ReceiverOrder,
    /// Receiver groups (`GpuScene::receiver_groups`).
    ReceiverGroups,
    /// The hierarchical gather's item lists (`GpuScene::group_items`).
    GroupItems,
    /// The sparse gather's blend lists (`GpuScene::blend_items`).
    BlendItems,
    /// Each level of detail's vertices (`GpuScene::level_vertices`).
    LevelVertices,
    /// Per sample, its atlas texel (x | y << 16) under the texture gather
    /// (`GpuScene::texel_coords`).
    TexelCoords,
    /// Per atlas texel of every texture-gathered object, its sample (`GpuScene::texel_index`).
    TexelIndex,
    /// Per vertex, its atlas texel (x | y << 16) under the texture gather (`GpuScene::vertex_texel`).
    VertexTexel,
    /// The texture gather's sum trees of texel power, its stage 0 (`GpuScene::texture_pyramid`).
    TexturePyramid,
    /// The shadow casters' hierarchy, for the splat's shadow rays (`GpuScene::bvh_nodes`).
    BvhNodes,
    /// Its triangles in leaf order (`GpuScene::bvh_triangles`).
    BvhTriangles,
    /// The between-points single scattering's kernel tables (`GpuScene::beam_tables`).
    BeamTables,
    /// Its per-node aggregates, its stage 0 (`GpuScene::beam_nodes`).
    BeamNodes,
    /// Its per-sample records, its stage 0 (`GpuScene::beam_sources`).
    BeamSources,
    /// Its density correction's denominator per vertex (`GpuScene::beam_norms`).
    BeamNorms,
    /// Per receiver of the whole mesh, the items of its walk (`GpuScene::beam_items`).
    BeamItems,
    /// Exitance at the samples, the sparse gather's stage 0 (owned by `GatherSparsePass`).
    SampleExitance,
    /// The shadow-map array (`FrameTargets::shadow_maps`).
    ShadowMaps,
    /// The own HDR image (`FrameTargets::camera`).
    Hdr,
    /// The pixel gather's surface image (`FrameTargets::camera`).
    Surface,
    /// The own camera depth (`FrameTargets::camera`).
    CameraDepth,
    /// The host's colour attachment (`HostTarget::color`).
    HostColor,
    /// The host's depth attachment (`HostTarget::depth`).
    HostDepth,
    /// The tone map's RGBA8 output (owned by `TonemapPass`).
    Tonemapped,
    /// The tone map's non-finite counter (owned by `TonemapPass`).
    TonemapCounters,
}

impl Resource {
    /// The name the GLSL gives it: a buffer's block name, an image's variable name.
    pub fn glsl_name(self) -> &'static str {
        use Resource::*;
        match self {
            Vertices => "Vertices",
            Objects => "Objects",
            Lights => "Lights",
            Samples => "Samples",
            Splat => "Splat",
            SplatEnvironment => "SplatEnvironment",
            Exitance => "Exitance",
            EnvironmentIrradiance => "EnvironmentIrradiance",
            LocalExitance => "LocalExitance",
            VertexBoundary => "VertexBoundary",
            TreeNodes => "TreeNodes",
            TreeOrder => "TreeOrder",
            NodePower => "NodePower",
            ReceiverOrder => "ReceiverOrder",
            ReceiverGroups => "ReceiverGroups",
            GroupItems => "GroupItems",
            BlendItems => "BlendItems",
            LevelVertices => "LevelVertices",
            SampleExitance => "SampleExitance",
            TexelCoords => "TexelCoords",
            TexelIndex => "TexelIndex",
            VertexTexel => "VertexTexel",
            TexturePyramid => "TexturePyramid",
            BvhNodes => "BvhNodes",
            BvhTriangles => "BvhTriangles",
            BeamTables => "BeamTables",
            BeamNodes => "BeamNodes",
            BeamSources => "BeamSources",
            BeamNorms => "BeamNorms",
            BeamItems => "BeamItems",
            ShadowMaps => "shadow_maps",
            Hdr => "hdr",
            Surface => "surface",
            CameraDepth => "camera_depth",
            HostColor => "host_color",
            HostDepth => "host_depth",
            Tonemapped => "Tonemapped",
            TonemapCounters => "Counters",
        }
    }

    /// `binding` under this resource's GLSL name, for a descriptor set.
    pub fn bind(self, binding: Binding<'_>) -> Named<'_> {
        Named { name: self.glsl_name(), binding }
    }
}

/// What the host reads back after a frame's fence (exitance, splat and sky-light readback, the
/// tone-mapped image), so every frame makes their last writes visible to the host.
pub const HOST_READ: [Resource; 5] = [
    Resource::Splat,
    Resource::Exitance,
    Resource::EnvironmentIrradiance,
    Resource::Tonemapped,
    Resource::TonemapCounters,
];

/// Every resource that is a `GpuScene` buffer (`Resources::buffer`).
pub const SCENE_BUFFERS: [Resource; 29] = [
    Resource::Vertices,
    Resource::Objects,
    Resource::Lights,
    Resource::Samples,
    Resource::Splat,
    Resource::SplatEnvironment,
    Resource::Exitance,
    Resource::EnvironmentIrradiance,
    Resource::LocalExitance,
    Resource::VertexBoundary,
    Resource::TreeNodes,
    Resource::TreeOrder,
    Resource::NodePower,
    Resource::ReceiverOrder,
    Resource::ReceiverGroups,
    Resource::GroupItems,
    Resource::BlendItems,
    Resource::LevelVertices,
    Resource::TexelCoords,
    Resource::TexelIndex,
    Resource::VertexTexel,
    Resource::TexturePyramid,
    Resource::BvhNodes,
    Resource::BvhTriangles,
    Resource::BeamTables,
    Resource::BeamNodes,
    Resource::BeamSources,
    Resource::BeamNorms,
    Resource::BeamItems,
];

/// One declared access of a pass (`gpu::Use` over `Resource`).
pub type Use = crate::gpu::Use<Resource>;

/// `access` reads `resource`.
pub const fn read(resource: Resource, access: Access) -> Use {
    Use::new(resource, access)
}

/// `access` writes `resource`, keeping what it does not overwrite.
pub const fn write(resource: Resource, access: Access) -> Use {
    Use::new(resource, access)
}

/// `access` overwrites all of image `resource` (its old contents are dropped).
pub const fn overwrite(resource: Resource, access: Access) -> Use {
    Use::overwrite(resource, access)
}

/// The declaration of a compute pass that touches exactly the resources it binds: each of
/// `writes` written, every other binding read (an image sampled, a buffer as storage). One line
/// per pass: `compute_uses(&BINDINGS, &[Resource::Splat])`.
pub fn compute_uses(bindings: &[Resource], writes: &[Resource]) -> Vec<Use> {
    bindings
        .iter()
        .map(|&r| match r {
            _ if writes.contains(&r) => write(r, Access::ComputeWrite),
            Resource::ShadowMaps | Resource::Hdr | Resource::Surface => read(r, Access::ComputeSampledRead),
            _ => read(r, Access::ComputeRead),
        })
        .collect()
}

/// The registry of the frame's shared resources: the scene's buffers and the frame targets.
/// Passes bind from it by name, so no binding list restates which buffer is which.
#[derive(Clone, Copy)]
pub struct Resources<'a> {
    /// The scene's buffers.
    pub scene: &'a GpuScene,
    /// The shadow maps and camera images.
    pub targets: &'a FrameTargets,
}

impl<'a> Resources<'a> {
    /// The buffer behind a `GpuScene` resource, if it is one.
    pub fn buffer(&self, resource: Resource) -> Option<&'a Buffer> {
        use Resource::*;
        let s = self.scene;
        Some(match resource {
            Vertices => &s.vertices,
            Objects => &s.objects,
            Lights => &s.lights,
            Samples => &s.samples,
            Splat => &s.splat,
            SplatEnvironment => &s.splat_environment,
            Exitance => &s.exitance,
            EnvironmentIrradiance => &s.environment_irradiance,
            LocalExitance => &s.local_exitance,
            VertexBoundary => &s.vertex_boundary,
            TreeNodes => &s.tree_nodes,
            TreeOrder => &s.tree_order,
            NodePower => &s.node_power,
            ReceiverOrder => &s.receiver_order,
            ReceiverGroups => &s.receiver_groups,
            GroupItems => &s.group_items,
            BlendItems => &s.blend_items,
            LevelVertices => &s.level_vertices,
            TexelCoords => &s.texel_coords,
            TexelIndex => &s.texel_index,
            VertexTexel => &s.vertex_texel,
            TexturePyramid => &s.texture_pyramid,
            BvhNodes => &s.bvh_nodes,
            BvhTriangles => &s.bvh_triangles,
            BeamTables => &s.beam_tables,
            BeamNodes => &s.beam_nodes,
            BeamSources => &s.beam_sources,
            BeamNorms => &s.beam_norms,
            BeamItems => &s.beam_items,
            _ => return None,
        })
    }

    /// `resource` as a descriptor binding under its GLSL name: a scene buffer, or a frame
    /// target's image with its sampler and the layout its readers find it in. An error names a
    /// resource this registry does not hold (a pass's own, or a camera image of a host target).
    pub fn bind(&self, resource: Resource) -> GpuResult<Named<'a>> {
        if let Some(buffer) = self.buffer(resource) {
            return Ok(resource.bind(Binding::Buffer(buffer)));
        }
        self.targets
            .binding(resource)
            .map(|b| resource.bind(b))
            .ok_or_else(|| GpuError::Invalid(format!("{resource:?} is not a shared resource of this renderer")))
    }

    /// Every resource of `list` bound in order (binding i = `list[i]`).
    pub fn bind_all(&self, list: &[Resource]) -> GpuResult<Vec<Named<'a>>> {
        list.iter().map(|&r| self.bind(r)).collect()
    }
}

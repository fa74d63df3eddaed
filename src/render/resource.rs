//! The frame's resources, each declared once: its `Resource` name, its GLSL block or image
//! name, and, for a buffer of the scene's GPU data, the `SceneBuffers` field that holds it. The
//! enum, `Resource::glsl_name`, `SCENE_BUFFERS` and the buffer lookup all follow from the one
//! list in `declare_resources!` below, so a new scene buffer is one line there plus its upload
//! (`GpuScene::new`).
//!
//! What a pass does with a resource is a `Use`: `read`, `write` or `overwrite`, three calls the
//! barrier tracker tells apart (`gpu::Hazards`).

use crate::gpu::{Access, Binding, Buffer, Named};

/// The one declaration of every resource: `Name: field = "GlslName"` for a scene buffer (held in
/// `SceneBuffers::field`), `Name = "glsl_name"` for the rest (frame targets, the host's images,
/// and what a pass owns).
macro_rules! declare_resources {
    (
        scene { $( $(#[$sdoc:meta])* $scene:ident : $field:ident = $sglsl:literal, )* }
        other { $( $(#[$odoc:meta])* $other:ident = $oglsl:literal, )* }
    ) => {
        /// A resource of the frame: the scene's buffers (`SceneBuffers`), the frame targets
        /// (`FrameTargets`), and the few that a pass owns. Each is one GLSL block or image name.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Resource {
            $( $(#[$sdoc])* $scene, )*
            $( $(#[$odoc])* $other, )*
        }

        impl Resource {
            /// The name the GLSL gives it: a buffer's block name, an image's variable name.
            pub fn glsl_name(self) -> &'static str {
                match self {
                    $( Resource::$scene => $sglsl, )*
                    $( Resource::$other => $oglsl, )*
                }
            }
        }

        /// Every resource that is a scene buffer (`SceneBuffers::get`).
        pub const SCENE_BUFFERS: &[Resource] = &[ $( Resource::$scene, )* ];

        /// The scene's buffers on the GPU, one per scene resource, made and filled by
        /// `GpuScene::new`.
        pub struct SceneBuffers {
            $( $(#[$sdoc])* pub(in crate::render) $field: Buffer, )*
        }

        impl SceneBuffers {
            /// The buffer behind `resource`, if it is a scene buffer.
            pub fn get(&self, resource: Resource) -> Option<&Buffer> {
                match resource {
                    $( Resource::$scene => Some(&self.$field), )*
                    _ => None,
                }
            }

            /// The buffer behind `resource` to write from the host, if it is a scene buffer.
            pub fn get_mut(&mut self, resource: Resource) -> Option<&mut Buffer> {
                match resource {
                    $( Resource::$scene => Some(&mut self.$field), )*
                    _ => None,
                }
            }

            $(
                $(#[$sdoc])*
                pub fn $field(&self) -> &Buffer {
                    &self.$field
                }
            )*
        }
    };
}

declare_resources! {
    scene {
        /// `VertexRecord` per vertex (`SceneBuffers::vertices`); also the vertex stream of the draws.
        Vertices: vertices = "Vertices",
        /// `ObjectRecord` per object (`SceneBuffers::objects`), rewritten by uploads.
        Objects: objects = "Objects",
        /// `Light` per prepared light (`SceneBuffers::lights`), rewritten by uploads.
        Lights: lights = "Lights",
        /// `SampleRecord` per sample (`SceneBuffers::samples`).
        Samples: samples = "Samples",
        /// `SplatRecord` per sample, the splat's output (`SceneBuffers::splat`).
        Splat: splat = "Splat",
        /// The environment's transmitted irradiance per sample, kept by the splat between frames
        /// (`SceneBuffers::splat_environment`).
        SplatEnvironment: splat_environment = "SplatEnvironment",
        /// Exitance per vertex, the vertex-wide gathers' output (`SceneBuffers::exitance`); also a
        /// vertex stream of shading.
        Exitance: exitance = "Exitance",
        /// Environment irradiance per vertex (`SceneBuffers::environment_irradiance`); also a vertex
        /// stream of shading.
        EnvironmentIrradiance: environment_irradiance = "EnvironmentIrradiance",
        /// The locally computed channels' exitance per vertex (`SceneBuffers::local_exitance`).
        LocalExitance: local_exitance = "LocalExitance",
        /// Distances to open boundaries per vertex (`SceneBuffers::vertex_boundary`).
        VertexBoundary: vertex_boundary = "VertexBoundary",
        /// The sample hierarchies' nodes (`SceneBuffers::tree_nodes`).
        TreeNodes: tree_nodes = "TreeNodes",
        /// The hierarchies' leaf order (`SceneBuffers::tree_order`).
        TreeOrder: tree_order = "TreeOrder",
        /// Power per node, the hierarchical gather's stage 0 (`SceneBuffers::node_power`).
        NodePower: node_power = "NodePower",
        /// Vertices in receiver-group order (`SceneBuffers::receiver_order`).
        ReceiverOrder: receiver_order = "ReceiverOrder",
        /// Receiver groups (`SceneBuffers::receiver_groups`).
        ReceiverGroups: receiver_groups = "ReceiverGroups",
        /// The hierarchical gather's item lists (`SceneBuffers::group_items`).
        GroupItems: group_items = "GroupItems",
        /// The sparse gather's blend lists (`SceneBuffers::blend_items`).
        BlendItems: blend_items = "BlendItems",
        /// Each level of detail's vertices (`SceneBuffers::level_vertices`).
        LevelVertices: level_vertices = "LevelVertices",
        /// Per sample, its atlas texel (x | y << 16) under the texture gather
        /// (`SceneBuffers::texel_coords`).
        TexelCoords: texel_coords = "TexelCoords",
        /// Per atlas texel of every texture-gathered object, its sample (`SceneBuffers::texel_index`).
        TexelIndex: texel_index = "TexelIndex",
        /// Per vertex, its atlas texel (x | y << 16) under the texture gather (`SceneBuffers::vertex_texel`).
        VertexTexel: vertex_texel = "VertexTexel",
        /// The texture gather's sum trees of texel power, its stage 0 (`SceneBuffers::texture_pyramid`).
        TexturePyramid: texture_pyramid = "TexturePyramid",
        /// The shadow casters' hierarchy, for the splat's shadow rays (`SceneBuffers::bvh_nodes`).
        BvhNodes: bvh_nodes = "BvhNodes",
        /// Its triangles in leaf order (`SceneBuffers::bvh_triangles`).
        BvhTriangles: bvh_triangles = "BvhTriangles",
        /// The between-points single scattering's kernel tables (`SceneBuffers::beam_tables`).
        BeamTables: beam_tables = "BeamTables",
        /// Its per-node aggregates, its stage 0 (`SceneBuffers::beam_nodes`).
        BeamNodes: beam_nodes = "BeamNodes",
        /// Its per-sample records, its stage 0 (`SceneBuffers::beam_sources`).
        BeamSources: beam_sources = "BeamSources",
        /// Its density correction's denominator per vertex (`SceneBuffers::beam_norms`).
        BeamNorms: beam_norms = "BeamNorms",
        /// Per receiver of the whole mesh, the items of its walk (`SceneBuffers::beam_items`).
        BeamItems: beam_items = "BeamItems",
        /// The transport kernels' patches (`SceneBuffers::transport_patches`).
        TransportPatches: transport_patches = "TransportPatches",
        /// Per patch, its vertices and samples (`SceneBuffers::transport_items`).
        TransportItems: transport_items = "TransportItems",
        /// The kernels' `W` (`SceneBuffers::transport_matrix`).
        TransportMatrix: transport_matrix = "TransportMatrix",
        /// Per patch, this frame's flux and exitances (`SceneBuffers::transport_sums`).
        TransportSums: transport_sums = "TransportSums",
        /// Per vertex of a kernel's object, its patch neighbours (`SceneBuffers::transport_neighbours`).
        TransportNeighbours: transport_neighbours = "TransportNeighbours",
        /// Per patch record, the splat generation that last needed its vertices' dipole values
        /// (`glsl/receiver_view.comp`; `SceneBuffers::transport_needed`).
        TransportNeeded: transport_needed = "TransportNeeded",
        /// Per vertex of a kernel's object, its dipole exitance and the generation it was
        /// gathered under (`glsl/transport.comp`; `SceneBuffers::transport_dipole`).
        TransportDipole: transport_dipole = "TransportDipole",
        /// Per vertex, its facing cone (`mesh::facing::vertex_cones`; `SceneBuffers::receiver_cones`).
        ReceiverCones: receiver_cones = "ReceiverCones",
        /// Per vertex, the splat generation its exitance was gathered under and whether this
        /// frame gathers it (`glsl/receiver_view.comp`; `SceneBuffers::receiver_state`).
        ReceiverState: receiver_state = "ReceiverState",
    }
    other {
        /// Exitance at the samples, the sparse gather's stage 0 (owned by `GatherSparsePass`).
        SampleExitance = "SampleExitance",
        /// The shadow-map array (`FrameTargets::shadow_maps`).
        ShadowMaps = "shadow_maps",
        /// The own HDR image (`FrameTargets::camera`).
        Hdr = "hdr",
        /// The pixel gather's surface image (`FrameTargets::camera`).
        Surface = "surface",
        /// The own camera depth (`FrameTargets::camera`).
        CameraDepth = "camera_depth",
        /// The host's colour attachment (`HostTarget::color`).
        HostColor = "host_color",
        /// The host's depth attachment (`HostTarget::depth`).
        HostDepth = "host_depth",
        /// The tone map's RGBA8 output (owned by `TonemapPass`).
        Tonemapped = "Tonemapped",
        /// The tone map's non-finite counter (owned by `TonemapPass`).
        TonemapCounters = "Counters",
    }
}

impl Resource {
    /// `binding` under this resource's GLSL name, for a descriptor set.
    pub fn bind(self, binding: Binding<'_>) -> Named<'_> {
        Named { name: self.glsl_name(), binding }
    }
}

/// What the host reads back after a frame's fence (exitance, splat and sky-light readback, the
/// tone-mapped image), so every frame makes their last writes visible to the host.
pub const HOST_READ: [Resource; 6] = [
    Resource::Splat,
    Resource::Exitance,
    Resource::LocalExitance,
    Resource::EnvironmentIrradiance,
    Resource::Tonemapped,
    Resource::TonemapCounters,
];

/// One declared access of a pass (`gpu::Use` over `Resource`).
pub type Use = crate::gpu::Use<Resource>;

/// `access`, which must not write, reads `resource`.
pub const fn read(resource: Resource, access: Access) -> Use {
    Use::read(resource, access)
}

/// `access` writes `resource`, keeping what it does not overwrite.
pub const fn write(resource: Resource, access: Access) -> Use {
    Use::write(resource, access)
}

/// `access` overwrites all of image `resource` (its old contents are dropped).
pub const fn overwrite(resource: Resource, access: Access) -> Use {
    Use::overwrite(resource, access)
}

/// [`compute_uses`] of a pass that reads what it writes: each of `read_write` both read and
/// written (`Access::ComputeReadWrite`), every other binding read. For a pass that keeps part
/// of a buffer, or whose later dispatches read what its earlier ones wrote.
pub fn compute_uses_read_write(bindings: &[Resource], read_write: &[Resource]) -> Vec<Use> {
    let mut uses = compute_uses(bindings, &[]);
    for u in uses.iter_mut().filter(|u| read_write.contains(&u.resource)) {
        *u = write(u.resource, Access::ComputeReadWrite);
    }
    uses
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

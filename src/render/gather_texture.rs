//! Texture-space gather pass (`glsl/gather_texture.comp`), for `render.gather = "texture"`,
//! after Chang, Lin, Ho, Huang and Chuang, *Real-Time Translucent Rendering Using GPU-based
//! Texture Space Importance Sampling* (Eurographics 2008).
//!
//! The object's samples are the texels of its atlas (`mesh::atlas`), so the splat computes each
//! texel's transmitted irradiance `E_i` with the same shadow maps as for any sample. The dipole
//! sum at a receiver `x` (seed Eq. 11 with the near field of `optics::kernel`) over the texels,
//! `M(x) = sum_i E_i A_i K(x, x_i) + near(x)`, is split by a window `W(x)` of
//! `(2h + 1)^2` texels around the receiver's own texel (`h` covers six times the widest channel's RMS
//! profile radius, at most 8 texels: `mesh::atlas::window_radius`):
//!
//! `M(x) = [sum_{i in W} E_i A_i K_i + near over W]  +  sum_{i not in W} E_i A_i K_i`.
//!
//! The first bracket is summed exactly. The second is estimated from `N` texels `i_k` drawn
//! with probability `p_i = P_i / sum_j P_j`, `P_i = (E_r + E_g + E_b)_i A_i`:
//! `G(x) = (1/N) sum_k [i_k not in W] E_{i_k} A_{i_k} K_{i_k} / p_{i_k}`, whose expectation is the
//! second sum exactly wherever `p_i > 0` for every texel with light (a texel without power adds
//! nothing either way): the estimator is unbiased for the dipole sum over the texels. Its
//! variance is what `tests/texture.rs` and the study measure.
//!
//! The draw descends a 4-ary sum tree over the texels in Morton order: a mip pyramid of `P`
//! (each node the sum of four children), built by stage 0 one depth per dispatch from the
//! splat, root last; `p_i` is the product of the branch probabilities on the way down.
//! Chang et al. importance-sample the irradiance texture in the same spirit (a hierarchical
//! warp of it), and add a local term from a texture-space filter for what lies near the
//! receiver; here the local term is the exact sum over the window, so the only error left is the
//! global term's variance.
//!
//! Random numbers: a hash of (receiver vertex, sample, depth) (`reference::texture::random`),
//! fixed per receiver: every frame of a static scene draws the same texels, so it does not
//! flicker (the temporal difference is 0), and the GPU and its f64 twin
//! (`reference::texture::gather`) draw the same ones.
//!
//! Bindings: `BINDINGS`, in binding order. Push: `GatherTexturePush`.

use super::graph::{Resource, Resources, Use, compute_uses, read, write};
use super::pass::{FrameInputs, RenderPass};
use crate::gpu::{Access, ComputePipeline, DescriptorSet, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

/// `GatherTexturePush` in glsl/gather_texture.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GatherTexturePush {
    /// Index of the receiving translucent object (its `ObjectRecord`).
    pub object: u32,
    /// 0: one depth of the sum tree; 1: the gather.
    pub stage: u32,
    /// Stage 0: the depth built (`4^depth` nodes).
    pub depth: u32,
    /// The tree's depth: the texels are its leaves.
    pub levels: u32,
    /// The object's root in `GpuScene::texture_pyramid`.
    pub first_node: u32,
    /// The object's index map in `GpuScene::texel_index`.
    pub first_index: u32,
    /// Its atlas's texels per side.
    pub resolution: u32,
    /// Importance-sampled texels per receiver.
    pub samples: u32,
    /// The local window's half-width, in texels.
    pub radius: u32,
    /// Added to every hash (0 in frames).
    pub seed: u32,
    /// First entry of its level of detail's vertex list in `GpuScene::level_vertices`.
    pub first_entry: u32,
    /// Vertices in that list.
    pub receiver_count: u32,
}

/// glsl/gather_texture.comp's bindings, in binding order.
const BINDINGS: [Resource; 11] = [
    Resource::Vertices,
    Resource::Samples,
    Resource::Splat,
    Resource::Objects,
    Resource::Exitance,
    Resource::VertexBoundary,
    Resource::LevelVertices,
    Resource::TexelCoords,
    Resource::TexelIndex,
    Resource::VertexTexel,
    Resource::TexturePyramid,
];

/// The texture gather: per translucent object the plan gathers, one dispatch per depth of its
/// sum tree, then one over the vertices of its level of detail, writing their exitance into
/// `GpuScene::exitance`.
pub struct GatherTexturePass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    samples: u32,
}

impl GatherTexturePass {
    /// The pipeline and one descriptor set over `BINDINGS`; `samples` per receiver
    /// (`render.texture_samples`).
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources, samples: u32) -> GpuResult<GatherTexturePass> {
        let pipeline = ComputePipeline::new(gpu, "gather_texture.comp")?;
        let set = pipeline.descriptor_set(&resources.bind_all(&BINDINGS)?)?;
        Ok(GatherTexturePass { pipeline, set, samples })
    }
}

impl RenderPass for GatherTexturePass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        compute_uses(&BINDINGS, &[Resource::Exitance, Resource::TexturePyramid])
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let step = [
            read(Resource::TexturePyramid, Access::ComputeRead),
            write(Resource::TexturePyramid, Access::ComputeWrite),
        ];
        // An object without an atlas (a scene prepared for another gather) keeps its exitance.
        let planned = || {
            let receivers = frame.scene.receivers.iter();
            receivers.filter(|r| {
                frame.plan.gathers(r.object as usize) && frame.scene.textures[r.object as usize].resolution > 0
            })
        };
        let push_of = |object: u32| {
            let t = frame.scene.textures[object as usize];
            GatherTexturePush {
                object,
                levels: t.levels,
                first_node: t.first_node,
                first_index: t.first_index,
                resolution: t.resolution,
                samples: self.samples,
                radius: t.radius,
                ..GatherTexturePush::default()
            }
        };
        for r in planned() {
            let base = push_of(r.object);
            for depth in (0..base.levels).rev() {
                let push = GatherTexturePush { depth, ..base };
                self.pipeline.dispatch(cmd, &self.set, &push, [1 << (2 * depth), 1, 1]);
                frame.before(cmd, &step);
            }
        }
        for r in planned() {
            let level = frame.scene.level(r.object as usize, frame.plan.level(r.object as usize));
            let push = GatherTexturePush {
                stage: 1,
                first_entry: level.first_entry,
                receiver_count: level.vertex_count,
                ..push_of(r.object)
            };
            self.pipeline.dispatch(cmd, &self.set, &push, [level.vertex_count, 1, 1]);
        }
    }
}

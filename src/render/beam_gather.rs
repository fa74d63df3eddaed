//! Between-points single-scattering pass (`glsl/beam_gather.comp`): for the channels a
//! material's `model` gives to single scattering between points (`scene::ScatteringModel`), the
//! exitance at the vertices of each such object's level of detail, from its samples' transmitted
//! irradiance and beam directions (`SplatRecord::beam`) through the kernel's table
//! (`optics::beam_table`). It runs in the gather's slot, after the dipole gather, and overwrites
//! those channels alone. Two stages per object, as the hierarchical gather's: stage 0 aggregates
//! each node of its sample hierarchy from this frame's splat (`BeamNodeRecord`, and the node's
//! stand-in as a `BeamSourceRecord`), one height per dispatch; stage 1 sums, per receiver, the
//! sources of its walk of the hierarchy, a node under `render.beam_opening` of its distance
//! standing in for its members (`ObjectBeams::opening`). The walk depends on the geometry alone,
//! so [`receiver_walks`] takes it once at upload with the density correction's denominator, and
//! stage 1 reads it (`ObjectBeams::lists`, within `render.beam_walk_mib`); past that budget
//! stage 1 takes it each frame, one source (a sample or a stand-in) per step.
//!
//! Bindings: `BINDINGS`, in binding order. Push: `BeamGatherPush`.

use super::graph::{Resource, Resources, Use, compute_uses_read_write, read, write};
use super::pass::{AfterGather, FrameInputs, RenderPass};
pub use super::beam_tables::{ObjectBeams, PackedBeams, ReceiverWalk, WalkItem, object_tables, pack_tables, receiver_walks, walk};
use crate::gpu::{Access, ComputePipeline, DescriptorSet, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

/// `BeamGatherPush` in glsl/beam_gather.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BeamGatherPush {
    /// x: the object; y: its receivers' first entry in `level_vertices` or `receiver_order`;
    /// z: their count; w: the channel mask.
    pub object: [u32; 4],
    /// x: its table's base in `GpuScene::beam_tables` (uvec4 entries); y: its root in
    /// `tree_nodes`; z: its node count; w: bit 0: the receivers are `receiver_order`'s (the
    /// whole mesh, absolute indices), else `level_vertices`' (a coarser level, object-relative);
    /// bit 1: their walks are read from `GpuScene::beam_items` (`ObjectBeams::lists`), else
    /// taken each frame.
    pub tree: [u32; 4],
    /// x: the critical cosine inside; y: `render.beam_opening`; z: the table's window radius in scene
    /// units; w: 0. (The channels share the table's distance axis, so their `sigma_t'` is not
    /// needed here.)
    pub critical: [f32; 4],
    /// xyz: `R1(1)` per channel; w: the reach in scene units.
    pub normal_total: [f32; 4],
    /// x: 0 aggregate the nodes, 1 gather; y, z: stage 0's nodes, `tree_order[y + k]` for
    /// `k < z` (one height of the hierarchy); w: the nodes' stand-ins' first entry in
    /// `GpuScene::beam_sources` (`GpuScene::beam_standins`).
    pub stage: [u32; 4],
}

/// glsl/beam_gather.comp's bindings, in binding order.
const BINDINGS: [Resource; 14] = [
    Resource::Vertices,
    Resource::Samples,
    Resource::Splat,
    Resource::Objects,
    Resource::Exitance,
    Resource::LevelVertices,
    Resource::BeamTables,
    Resource::TreeNodes,
    Resource::TreeOrder,
    Resource::ReceiverOrder,
    Resource::BeamNodes,
    Resource::BeamSources,
    Resource::BeamNorms,
    Resource::BeamItems,
];

/// Per gathered object with a between-points channel, glsl/beam_gather.comp's stage 0 (one
/// dispatch per height of its hierarchy) and stage 1 (one).
pub struct BeamGatherPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
}

impl BeamGatherPass {
    /// The pipeline and one descriptor set over `BINDINGS`; `None` when no object of the scene
    /// takes the model (the frame then records nothing for it).
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources) -> GpuResult<Option<BeamGatherPass>> {
        if resources.scene.beams.iter().all(Option::is_none) {
            return Ok(None);
        }
        let pipeline = ComputePipeline::new(gpu, "beam_gather.comp")?;
        let set = pipeline.descriptor_set(&resources.bind_all(&BINDINGS)?)?;
        Ok(Some(BeamGatherPass { pipeline, set }))
    }
}

impl AfterGather for BeamGatherPass {
    /// Whether this frame gathers an object with a between-points channel.
    fn runs(frame: &FrameInputs) -> bool {
        frame.scene.beams.iter().enumerate().any(|(i, b)| b.is_some() && frame.plan.gathers(i))
    }
}

impl RenderPass for BeamGatherPass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        // It keeps the dipole's channels: the exitance is read and written; stage 1 reads the
        // nodes stage 0 wrote.
        compute_uses_read_write(&BINDINGS, &[Resource::Exitance, Resource::BeamNodes, Resource::BeamSources])
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let planned = || {
            frame.scene.receivers.iter().enumerate().filter_map(|(j, r)| {
                let object = r.object as usize;
                frame.scene.beams[object].filter(|_| frame.plan.gathers(object)).map(|b| (j, r, b))
            })
        };
        for (j, r, b) in planned() {
            for (h, &[first, count]) in frame.scene.node_heights[j].iter().enumerate() {
                if h > 0 {
                    // This height reads the nodes the heights before it wrote.
                    frame.before(cmd, &[write(Resource::BeamNodes, Access::ComputeReadWrite)]);
                }
                let base = frame.scene.beam_standins;
                let push = BeamGatherPush {
                    stage: [0, first, count, base],
                    ..Self::push(frame, r, &b, r.first_receiver, 0, 1)
                };
                self.pipeline.dispatch(cmd, &self.set, &push, [count, 1, 1]);
            }
        }
        frame.before(
            cmd,
            &[read(Resource::BeamNodes, Access::ComputeRead), read(Resource::BeamSources, Access::ComputeRead)],
        );
        for (_, r, b) in planned() {
            let object = r.object as usize;
            let level_index = frame.plan.level(object);
            let level = frame.scene.level(object, level_index);
            // The whole mesh's vertices in receiver-group order, where the walks of neighbouring
            // invocations are alike; a coarser level's list otherwise.
            let (first, count, grouped) = if level_index == 0 {
                (r.first_receiver, r.vertex_count, 1)
            } else {
                (level.first_entry, level.vertex_count, 0)
            };
            // A coarser level's vertices are the whole mesh's, with the same walks.
            let grouped = grouped | u32::from(b.lists) << 1;
            let push = Self::push(frame, r, &b, first, count, grouped);
            self.pipeline.dispatch(cmd, &self.set, &push, [count, 1, 1]);
        }
    }
}

impl BeamGatherPass {
    /// Stage 1's push block for `count` receivers of `r` from `first` (`grouped`: `tree.w`).
    fn push(
        frame: &FrameInputs,
        r: &super::gpu_scene::Receiver,
        b: &ObjectBeams,
        first: u32,
        count: u32,
        grouped: u32,
    ) -> BeamGatherPush {
        let [r0, r1, r2] = b.normal_total;
        BeamGatherPush {
            object: [r.object, first, count, b.channels],
            tree: [b.table, r.first_node, r.node_count, grouped],
            critical: [b.mu_c, b.opening, b.window, 0.0],
            normal_total: [r0, r1, r2, b.reach],
            stage: [1, 0, 0, frame.scene.beam_standins],
        }
    }
}

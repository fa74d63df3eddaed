//! Transport-kernel pass (`glsl/transport.comp`): for each gathered object with
//! `material.model = "transport"` and a kernel attached (`optics::transport`,
//! `PreparedObject::transport`), the dipole's exitance at its vertices scaled per patch of its
//! surface to the radiative transfer through its own mesh. It runs in the gather's slot after the
//! dipole gather and the between-points pass (`pass::GatherThen`): stage 0 sums each patch's
//! transmitted flux and dipole exitance, stage 1 applies the kernel, stage 2 scales each vertex.
//!
//! Gathered visible-first, a frame scales only the vertices `receiver_view` marked, from the
//! dipole values stage 0 keeps per vertex (`Resource::TransportDipole`), and a frame that keeps
//! the splat's generation (a camera frame, a sweep's chunk) keeps each patch's `F`: stage 1
//! finds it stamped with the generation and returns.
//!
//! Bindings: `BINDINGS`, in binding order. Push: `TransportPush`.

use super::graph::{Resource, Resources, Use, compute_uses_read_write, read, write};
use super::pass::{AfterGather, FrameInputs, RenderPass};
use super::plan::ReceiverScope;
use super::transport_tables::LevelTransport;
use crate::gpu::{Access, ComputePipeline, DescriptorSet, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

/// `TransportPush` in glsl/transport.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TransportPush {
    /// x: the stage; y: the object's first patch; z: its patch count; w: the channels it
    /// scales (`LevelTransport::channels`).
    pub stage: [u32; 4],
    /// x: the object's first vertex; y: the level's vertex count; z: the object's first
    /// neighbour entry; w: the level's first entry in `level_vertices`.
    pub vertices: [u32; 4],
    /// x: the object's splat generation (`ReceiverScope::VisibleFirst`); y: 1 where the gather
    /// recomputed every receiver (`ReceiverScope::Every`), 0 where it took the ones
    /// `receiver_view` marked; z, w: 0.
    pub frame: [u32; 4],
}

/// glsl/transport.comp's bindings, in binding order.
const BINDINGS: [Resource; 11] = [
    Resource::Splat,
    Resource::Exitance,
    Resource::TransportPatches,
    Resource::TransportItems,
    Resource::TransportMatrix,
    Resource::TransportSums,
    Resource::TransportNeighbours,
    Resource::LevelVertices,
    Resource::Samples,
    Resource::ReceiverState,
    Resource::TransportDipole,
];

/// The three stages of glsl/transport.comp, one dispatch per object each.
pub struct TransportPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
}

impl TransportPass {
    /// The pipeline and one descriptor set over `BINDINGS`; `None` when no object of the scene
    /// has a kernel attached.
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources) -> GpuResult<Option<TransportPass>> {
        if resources.scene.transport.iter().all(Option::is_none) {
            return Ok(None);
        }
        let pipeline = ComputePipeline::new(gpu, "transport.comp")?;
        let set = pipeline.descriptor_set(&resources.bind_all(&BINDINGS)?)?;
        Ok(Some(TransportPass { pipeline, set }))
    }

    /// The gathered objects with a kernel this frame, at the level each is gathered at.
    fn planned<'a>(frame: &'a FrameInputs) -> impl Iterator<Item = (LevelTransport, ReceiverScope)> + 'a {
        (0..frame.scene.transport.len())
            .filter(|&i| frame.plan.gathers(i))
            .filter_map(|i| Some((frame.scene.transport_at(i, frame.plan.level(i))?, frame.plan.receivers(i))))
    }
}

impl AfterGather for TransportPass {
    /// Whether this frame gathers an object with a kernel.
    fn runs(frame: &FrameInputs) -> bool {
        Self::planned(frame).next().is_some()
    }
}

impl RenderPass for TransportPass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        // The exitance is read by stage 0 and written by stage 2; the sums by all three; the
        // dipole values written by stage 0 and read by stage 2.
        let rw = [Resource::Exitance, Resource::TransportSums, Resource::TransportDipole];
        compute_uses_read_write(&BINDINGS, &rw)
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let push = |stage, (t, scope): &(LevelTransport, ReceiverScope)| TransportPush {
            stage: [stage, t.patches[0], t.patches[1], t.channels],
            vertices: [t.vertices[0], t.vertices[1], t.first_neighbour, t.first_entry],
            frame: match *scope {
                ReceiverScope::VisibleFirst { generation, .. } => [generation, 0, 0, 0],
                ReceiverScope::Every { .. } => [0, 1, 0, 0],
            },
        };
        for t in Self::planned(frame) {
            self.pipeline.dispatch(cmd, &self.set, &push(0, &t), [t.0.patches[1], 1, 1]);
        }
        let stage0 = [Resource::TransportSums, Resource::TransportDipole];
        frame.before(cmd, &stage0.map(|r| write(r, Access::ComputeReadWrite)));
        for t in Self::planned(frame) {
            self.pipeline.dispatch(cmd, &self.set, &push(1, &t), [t.0.patches[1], 1, 1]);
        }
        frame.before(cmd, &[read(Resource::TransportSums, Access::ComputeRead)]);
        for t in Self::planned(frame) {
            self.pipeline.dispatch(cmd, &self.set, &push(2, &t), [t.0.vertices[1], 1, 1]);
        }
    }
}

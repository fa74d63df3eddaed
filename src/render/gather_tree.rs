//! Hierarchical-gather pass (`glsl/gather_tree.comp`), for `render.gather = "hierarchical"`:
//! the vertex gather's dipole sum with far clusters of samples standing in for their members
//! (after Jensen and Buhler 2002). Per translucent object the plan gathers, stage 0 aggregates
//! each node of its sample hierarchy (`sampling::SampleTree`) from this frame's splat into the
//! node power, bottom-up, one height per dispatch (`group_gather::Stage0::ByHeight`), then stage 1 sums, for every vertex, its own list of samples and nodes (the cut
//! `sampling::SampleTree::cut` chose about that vertex, built once in `GpuScene::new`; one
//! record per receiver in `receiver_groups`, in group order so that neighbouring lanes walk
//! similar lists). The two stages' shape is `group_gather`'s. `render.gather_epsilon` is the
//! accuracy knob: the solid-angle bound below which a node is used whole; 0 is the flat sum.
//! `reference::tree::gather` is its f64 twin.
//!
//! Bindings: `BINDINGS`, in binding order. Push: `GatherTreePush`.

use super::graph::{Resource, Resources, Use, compute_uses};
use super::group_gather::{GroupGather, Stage0};
use super::pass::{FrameInputs, RenderPass};
use super::receiver_view::ReceiverView;
use super::target::DepthTest;
use crate::gpu::{ComputePipeline, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

/// `GatherTreePush` in glsl/gather_tree.comp: the two-stage gathers' push block
/// (0: aggregate the nodes; 1: gather at the vertices).
pub use super::group_gather::GroupGatherPush as GatherTreePush;

/// glsl/gather_tree.comp's bindings, in binding order.
const BINDINGS: [Resource; 13] = [
    Resource::Vertices,
    Resource::Samples,
    Resource::Splat,
    Resource::Objects,
    Resource::TreeNodes,
    Resource::TreeOrder,
    Resource::NodePower,
    Resource::ReceiverOrder,
    Resource::ReceiverGroups,
    Resource::GroupItems,
    Resource::Exitance,
    Resource::VertexBoundary,
    Resource::ReceiverState,
];

/// The hierarchical gather: two dispatches of glsl/gather_tree.comp per translucent object the
/// plan gathers, writing exitance at its vertices into `GpuScene::exitance`.
pub struct GatherTreePass {
    stages: GroupGather,
}

impl GatherTreePass {
    /// The pipeline and one descriptor set over `BINDINGS` (whose group items `GpuScene::new`
    /// built for the scene's `render.gather_epsilon`).
    /// `depth` is the shading pass's depth test, which decides whether it culls hidden faces
    /// (and so whether the pick of receivers tests their facing).
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources, depth: DepthTest) -> GpuResult<GatherTreePass> {
        let pipeline = ComputePipeline::new(gpu, "gather_tree.comp")?;
        let set = pipeline.descriptor_set(&resources.bind_all(&BINDINGS)?)?;
        let mut stages = GroupGather::new(pipeline, set, Resource::NodePower, Stage0::ByHeight);
        stages.view = Some(ReceiverView::new(gpu, resources, depth)?);
        Ok(GatherTreePass { stages })
    }
}

impl RenderPass for GatherTreePass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        // What the pick binds too is declared once, as the pick uses it: it reads and writes
        // the receiver state before stage 1 reads it.
        let view = ReceiverView::uses();
        let mut uses = compute_uses(&BINDINGS, &[Resource::NodePower, Resource::Exitance]);
        uses.retain(|u| !view.iter().any(|v| v.resource == u.resource));
        uses.extend(view);
        uses
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        self.stages.record(cmd, frame);
    }
}

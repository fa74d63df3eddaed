//! The shape the two two-stage gathers share (`gather_tree`, `gather_sparse`): stage 0 runs
//! over something of each object the plan gathers (its hierarchy's nodes, or its samples) into
//! a buffer stage 1 reads; stage 1 runs one invocation per receiver, one workgroup per receiver
//! group (`sampling::ReceiverGroups`, `RECEIVER_GROUP_SIZE` vertices) of the same objects, into
//! the per-vertex exitance (the sparse gather's lists are per group, the hierarchical one's per
//! receiver). Both stages run over the plan's receivers only: an object the plan does
//! not gather this frame has no fresh stage-0 output, and its exitance must stay as it was.

use super::gpu_scene::Receiver;
use super::graph::{Resource, read, write};
use super::pass::FrameInputs;
use super::plan::ReceiverScope;
use super::receiver_view::ReceiverView;
use crate::gpu::{Access, ComputePipeline, DescriptorSet};
use ash::vk;

/// The push block of both two-stage gathers (`GatherTreePush` in glsl/gather_tree.comp,
/// `GatherSparsePush` in glsl/gather_sparse.comp, which have the same fields).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GroupGatherPush {
    /// Index of the receiving translucent object (its `ObjectRecord`).
    pub object: u32,
    /// 0 or 1.
    pub stage: u32,
    /// The object's root in `GpuScene::tree_nodes` (the nearest-sample fallback walks it).
    pub first_node: u32,
    /// Its node count.
    pub node_count: u32,
    /// Its first entry in `GpuScene::receiver_order`.
    pub first_receiver: u32,
    /// Its first group in `GpuScene::receiver_groups`.
    pub first_group: u32,
    /// Receivers at the level of detail gathered: stage 1's threads.
    pub receiver_count: u32,
    /// Stage 0 of the hierarchical gather: the first entry in `GpuScene::tree_order` of the
    /// nodes this dispatch aggregates (one height of the hierarchy); 0 otherwise.
    pub first_listed: u32,
    /// Their count: the dispatch's threads.
    pub listed_count: u32,
    /// Stage 1 of the hierarchical gather: 1 to gather only the receivers
    /// `receiver_view` picked; 0 otherwise.
    pub only_picked: u32,
}

impl GroupGatherPush {
    /// The push block for `stage` of a dispatch over `receiver`.
    pub fn new(receiver: &Receiver, stage: u32) -> GroupGatherPush {
        GroupGatherPush {
            object: receiver.object,
            stage,
            first_node: receiver.first_node,
            node_count: receiver.node_count,
            first_receiver: receiver.first_receiver,
            first_group: receiver.first_group,
            receiver_count: receiver.vertex_count,
            first_listed: 0,
            listed_count: 0,
            only_picked: 0,
        }
    }
}

/// What a two-stage gather's stage 0 runs over.
#[derive(Clone, Copy, Debug)]
pub(super) enum Stage0 {
    /// One dispatch per object, this many threads (its samples).
    Threads(fn(&Receiver) -> u32),
    /// The object's hierarchy one height at a time, leaves first (`GpuScene::node_heights`),
    /// each dispatch reading what the ones before it wrote.
    ByHeight,
}

/// A two-stage gather's pipeline, its set, and what its stage 0 writes for stage 1.
pub(super) struct GroupGather {
    pub pipeline: ComputePipeline,
    pub set: DescriptorSet,
    /// Stage 0's output, read by stage 1.
    pub handoff: Resource,
    /// What stage 0 runs over: the sparse gather's samples, or the hierarchy by height.
    pub stage0: Stage0,
    /// The hierarchical gather's pick of receivers before stage 1, for the objects the plan
    /// gathers visible-first; `None`: every receiver.
    pub view: Option<ReceiverView>,
}

impl GroupGather {
    /// `pipeline` must have `RECEIVER_GROUP_SIZE` as its local size: its workgroups are
    /// receiver groups.
    pub fn new(pipeline: ComputePipeline, set: DescriptorSet, handoff: Resource, stage0: Stage0) -> GroupGather {
        let n = crate::sampling::RECEIVER_GROUP_SIZE as u32;
        assert!(
            pipeline.groups([n, 1, 1]) == [1, 1, 1] && pipeline.groups([n + 1, 1, 1]) == [2, 1, 1],
            "{}: local size is not RECEIVER_GROUP_SIZE",
            pipeline.name()
        );
        GroupGather { pipeline, set, handoff, stage0, view: None }
    }

    /// The pick of receivers (`view`), stage 0 over the plan's receivers whose splat is new to
    /// the gather, the hand-off barrier, stage 1 over the same receivers at the level of detail
    /// the plan draws each at (`GpuScene::receiver_at`: the whole mesh where the scene built no
    /// coarser receivers), the picked ones alone where the plan says so. The pick goes first:
    /// every dispatch of the gather's pipeline binds the receiver state it writes.
    pub fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let planned =
            || frame.scene.receivers.iter().enumerate().filter(|(_, r)| frame.plan.gathers(r.object as usize));
        let at = |j: usize, r: &Receiver| frame.scene.receiver_at(j, frame.plan.level(r.object as usize));
        if let Some(view) = &self.view {
            let picks: Vec<_> = planned().map(|(j, r)| (at(j, r), frame.plan.receivers(r.object as usize))).collect();
            view.record(cmd, frame, &picks);
        }
        for (j, r) in planned().filter(|(_, r)| frame.plan.receivers(r.object as usize).fresh()) {
            self.record_stage0(cmd, frame, j, r);
        }
        frame.before(cmd, &[read(self.handoff, Access::ComputeRead)]);
        for (j, r) in planned() {
            let scope = frame.plan.receivers(r.object as usize);
            let picked = self.view.is_some() && matches!(scope, ReceiverScope::VisibleFirst { .. });
            let at = at(j, r);
            let push = GroupGatherPush { only_picked: u32::from(picked), ..GroupGatherPush::new(at, 1) };
            self.pipeline.dispatch(cmd, &self.set, &push, [at.vertex_count, 1, 1]);
        }
    }

    /// Stage 0 for entry `j` of the scene's receivers, `r`.
    fn record_stage0(&self, cmd: vk::CommandBuffer, frame: &FrameInputs, j: usize, r: &Receiver) {
        match self.stage0 {
            Stage0::Threads(threads) => {
                self.pipeline.dispatch(cmd, &self.set, &GroupGatherPush::new(r, 0), [threads(r), 1, 1]);
            }
            Stage0::ByHeight => {
                for (h, &[first_listed, listed_count]) in frame.scene.node_heights[j].iter().enumerate() {
                    if h > 0 {
                        // This height reads the nodes the heights before it wrote.
                        frame.before(cmd, &[write(self.handoff, Access::ComputeReadWrite)]);
                    }
                    let push = GroupGatherPush { first_listed, listed_count, ..GroupGatherPush::new(r, 0) };
                    self.pipeline.dispatch(cmd, &self.set, &push, [listed_count, 1, 1]);
                }
            }
        }
    }
}

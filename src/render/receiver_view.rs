//! The receivers a visible-first hierarchical gather recomputes (`glsl/receiver_view.comp`): a
//! step of `gather_tree` before its stage 1, one dispatch per object whose plan scopes its
//! receivers `VisibleFirst` (`plan::receivers`). It marks in `ReceiverState` the receivers not
//! yet gathered under the object's splat generation that an eye may see or that fall in this
//! frame's chunk of the sweep; stage 1 gathers those alone.
//!
//! Bindings: `BINDINGS`, in binding order. Push: `ReceiverViewPush`.

use super::cull::{culled_faces, hidden_faces};
use super::gpu_scene::Receiver;
use super::graph::{Resource, Resources, Use, compute_uses_read_write};
use super::pass::FrameInputs;
use super::plan::{ReceiverScope, Sweep, View};
use super::target::{DepthConvention, DepthTest};
use crate::gpu::{ComputePipeline, DescriptorSet, Gpu, GpuResult};
use crate::mesh::enclosure;
use crate::mesh::facing::{faces_eye, longest_edge, vertex_cones};
use crate::scene::build::PreparedObject;
use ash::vk;
use std::sync::Arc;

/// glsl/receiver_view.comp's bindings, in binding order.
const BINDINGS: [Resource; 4] =
    [Resource::Vertices, Resource::ReceiverOrder, Resource::ReceiverCones, Resource::ReceiverState];

/// Pick the receivers an eye may see (`VIEW_TEST` in the GLSL).
const VIEW_TEST: u32 = 1;
/// Test the facing cone too: the shading pass culls the faces no eye ray reaches.
const FACING_TEST: u32 = 2;

/// `ReceiverViewPush` in glsl/receiver_view.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ReceiverViewPush {
    /// World -> clip of the camera.
    pub view_proj: [[f32; 4]; 4],
    /// `[e, 1]` for a perspective eye at `e` (`[0; 4]` with no facing test otherwise).
    pub eye: [f32; 4],
    /// The level's first entry in `GpuScene::receiver_order`.
    pub first_receiver: u32,
    /// Its receivers: the dispatch's threads.
    pub receiver_count: u32,
    /// The object's splat generation.
    pub generation: u32,
    /// `VIEW_TEST | FACING_TEST`.
    pub flags: u32,
    /// This frame's chunk of the sweep, in receiver order: first and count.
    pub sweep: [u32; 2],
    /// The drawn level's longest edge (`LevelRange::reach`).
    pub reach: f32,
    /// Pads the block to 16 bytes.
    pub pad: u32,
}

/// The f32 twin of the pick's view test on the host: the vertices (object-relative, ascending)
/// of `object`'s level `level` that an eye through `view` may see (`mesh::facing::faces_eye`
/// where the shading pass culls hidden faces, with `convention`'s depth, and the frustum widened
/// by the level's longest edge), as `glsl/receiver_view.comp` picks them on a frame of change.
pub fn seen_receivers(object: &PreparedObject, level: usize, view: &View, convention: DepthConvention) -> Vec<u32> {
    let positions = object.mesh.positions();
    let levels = || object.levels.iter().map(|l| (&l.triangles[..], enclosure(positions, &l.triangles)));
    let cones = vertex_cones(positions, levels());
    let Some(drawn) = object.levels.get(level) else { return Vec::new() };
    let reach = longest_edge(positions, &drawn.triangles);
    let bounds = drawn.bounds(positions);
    let perspective = view.view_proj.row(3).truncate() != glam::Vec3::ZERO;
    let culls = hidden_faces(enclosure(positions, &drawn.triangles), bounds, view.view_proj, convention);
    let facing = perspective && culls != vk::CullModeFlags::NONE;
    let eye = view.eye.extend(1.0).to_array();
    drawn
        .vertices
        .iter()
        .copied()
        .filter(|&v| {
            let x = positions[v as usize];
            view.sees(x, reach) && (!facing || faces_eye(cones[v as usize], x, eye))
        })
        .collect()
}

/// The pipeline and its set, and the depth test that decides whether shading culls.
pub struct ReceiverView {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    depth: DepthTest,
}

impl ReceiverView {
    /// The pipeline and one descriptor set over `BINDINGS`; `depth` is the shading pass's.
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources, depth: DepthTest) -> GpuResult<ReceiverView> {
        let pipeline = ComputePipeline::new(gpu, "receiver_view.comp")?;
        let set = pipeline.descriptor_set(&resources.bind_all(&BINDINGS)?)?;
        Ok(ReceiverView { pipeline, set, depth })
    }

    /// What it reads, and the state it reads and writes.
    pub fn uses() -> Vec<Use> {
        compute_uses_read_write(&BINDINGS, &[Resource::ReceiverState])
    }

    /// Mark the receivers of `at` (object `at.object`'s receivers at the level drawn) that
    /// `scope` gathers; nothing for a scope of every receiver.
    pub fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs, at: &Receiver, scope: ReceiverScope) {
        let ReceiverScope::VisibleFirst { generation, sweep, .. } = scope else { return };
        let object = at.object as usize;
        let level = frame.scene.level(object, frame.plan.level(object));
        let perspective = frame.view_proj.row(3).truncate() != glam::Vec3::ZERO;
        let culls = self.depth.compare != vk::CompareOp::ALWAYS
            && culled_faces(frame.plan, &level, frame.view_proj, self.depth.convention) != vk::CullModeFlags::NONE;
        let facing = perspective && culls;
        let push = ReceiverViewPush {
            view_proj: frame.view_proj.to_cols_array_2d(),
            eye: if facing { frame.eye.extend(1.0).to_array() } else { [0.0; 4] },
            first_receiver: at.first_receiver,
            receiver_count: at.vertex_count,
            generation,
            flags: VIEW_TEST | if facing { FACING_TEST } else { 0 },
            sweep: sweep.map_or([0, 0], |s: Sweep| s.range(at.vertex_count)),
            reach: level.reach,
            pad: 0,
        };
        self.pipeline.dispatch(cmd, &self.set, &push, [at.vertex_count, 1, 1]);
    }
}

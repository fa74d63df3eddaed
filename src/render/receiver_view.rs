//! The receivers a visible-first hierarchical gather recomputes (`glsl/receiver_view.comp`): a
//! step of `gather_tree` before its stage 1, one dispatch per object whose plan scopes its
//! receivers `VisibleFirst` (`plan::receivers`). It marks in `ReceiverState` the receivers not
//! yet gathered under the object's splat generation that an eye may see or that fall in this
//! frame's chunk of the sweep; stage 1 gathers those alone. For an object whose exitance a
//! transport kernel scales (`transport`), two more stages add the vertices of every patch a
//! picked vertex blends, whose dipole value is older: the kernel's ratio needs each such patch's
//! mean dipole exitance, so they are gathered too (once per generation), and scaled in turn.
//!
//! Bindings: `BINDINGS`, in binding order. Push: `ReceiverViewPush`.

use super::cull::{culled_faces, hidden_faces};
use super::gpu_scene::Receiver;
use super::graph::{Resource, Resources, Use, compute_uses_read_write, read, write};
use super::pass::FrameInputs;
use super::plan::{ReceiverScope, Sweep, View};
use super::target::{DepthConvention, DepthTest};
use crate::gpu::{Access, ComputePipeline, DescriptorSet, Gpu, GpuResult};
use crate::mesh::enclosure;
use crate::mesh::facing::{faces_eye, longest_edge, vertex_cones};
use crate::optics::transport::TransportKernel;
use crate::scene::build::PreparedObject;
use ash::vk;
use std::sync::Arc;

/// glsl/receiver_view.comp's bindings, in binding order.
const BINDINGS: [Resource; 9] = [
    Resource::Vertices,
    Resource::ReceiverOrder,
    Resource::ReceiverCones,
    Resource::ReceiverState,
    Resource::TransportNeighbours,
    Resource::TransportPatches,
    Resource::TransportItems,
    Resource::TransportNeeded,
    Resource::TransportDipole,
];

/// Pick the receivers an eye may see (`VIEW_TEST` in the GLSL).
const VIEW_TEST: u32 = 1;
/// Test the facing cone too: the shading pass culls the faces no eye ray reaches.
const FACING_TEST: u32 = 2;
/// A transport kernel scales the object's exitance: mark the picked vertices to be scaled, and
/// gather what their patches need.
const KERNEL: u32 = 4;

/// `ReceiverState`'s y bit: stage 1 of the gather computes the vertex's dipole exitance.
pub const GATHER: u32 = 1;
/// `ReceiverState`'s y bit: the transport pass scales the vertex this frame.
pub const FINISH: u32 = 2;

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
    /// 0: the pick; for a kernel's object, 1: its picked vertices stamp their patches; 2: the
    /// stamped patches mark their vertices to gather.
    pub stage: u32,
    /// A kernel's object: the level's first patch record and patch count, the object's first
    /// neighbour entry and first vertex (`LevelTransport`); 0 otherwise.
    pub kernel: [u32; 4],
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

/// The host twin of the two stages for an object a transport kernel scales, on a frame of
/// change (no dipole value current): the vertices (object-relative, ascending) of `object`'s
/// level `level` that the gather computes when the pick chose `picked` (object-relative,
/// ascending): those, and every vertex of the level in a patch one of them blends
/// (`TransportKernel::vertex_neighbours`). `picked` itself where no kernel scales the object.
pub fn kernel_gathered(object: &PreparedObject, level: usize, picked: &[u32]) -> Vec<u32> {
    let (Some(kernel), Some(drawn)) =
        (object.transport.as_ref().filter(|_| object.wants_transport()), object.levels.get(level))
    else {
        return picked.to_vec();
    };
    let blends = TransportKernel::vertex_neighbours(&kernel.placed(&object.mesh), &object.mesh);
    let mut needed = vec![false; kernel.patches.len()];
    for &v in picked {
        blends[v as usize].iter().for_each(|&(p, _)| needed[p as usize] = true);
    }
    let in_needed = |v: u32| needed[kernel.patches.of_vertex[v as usize] as usize];
    drawn.vertices.iter().copied().filter(|&v| in_needed(v) || picked.binary_search(&v).is_ok()).collect()
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

    /// What it reads, and the state (and the kernels' stamps) it reads and writes.
    pub fn uses() -> Vec<Use> {
        compute_uses_read_write(&BINDINGS, &[Resource::ReceiverState, Resource::TransportNeeded])
    }

    /// Mark the receivers each of `picks` gathers (object `at.object`'s receivers at the level
    /// drawn, under `scope`; nothing for a scope of every receiver), then, for the objects a
    /// kernel scales, stamp their picked vertices' patches and mark those patches' vertices.
    /// Ends with the state readable by the gather.
    pub fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs, picks: &[(&Receiver, ReceiverScope)]) {
        let pushes: Vec<ReceiverViewPush> =
            picks.iter().filter_map(|&(at, scope)| self.push(frame, at, scope)).collect();
        for push in &pushes {
            self.pipeline.dispatch(cmd, &self.set, push, [push.receiver_count, 1, 1]);
        }
        let kernels: Vec<&ReceiverViewPush> = pushes.iter().filter(|p| p.flags & KERNEL != 0).collect();
        // Stage 1 reads the pick's marks, stage 2 the patches' stamps: each after a barrier.
        let stages = [(1, Resource::ReceiverState), (2, Resource::TransportNeeded)];
        for (stage, after) in stages.into_iter().filter(|_| !kernels.is_empty()) {
            frame.before(cmd, &[write(after, Access::ComputeReadWrite)]);
            for push in &kernels {
                let threads = if stage == 1 { push.receiver_count } else { push.kernel[1] };
                self.pipeline.dispatch(cmd, &self.set, &ReceiverViewPush { stage, ..**push }, [threads, 1, 1]);
            }
        }
        frame.before(cmd, &[read(Resource::ReceiverState, Access::ComputeRead)]);
    }

    /// The pick's push block for `at` under `scope`; `None` for a scope of every receiver.
    fn push(&self, frame: &FrameInputs, at: &Receiver, scope: ReceiverScope) -> Option<ReceiverViewPush> {
        let ReceiverScope::VisibleFirst { generation, sweep, .. } = scope else { return None };
        let object = at.object as usize;
        let level = frame.scene.level(object, frame.plan.level(object));
        let perspective = frame.view_proj.row(3).truncate() != glam::Vec3::ZERO;
        let culls = self.depth.compare != vk::CompareOp::ALWAYS
            && culled_faces(frame.plan, &level, frame.view_proj, self.depth.convention) != vk::CullModeFlags::NONE;
        let facing = perspective && culls;
        let kernel = frame.scene.transport_at(object, frame.plan.level(object));
        Some(ReceiverViewPush {
            view_proj: frame.view_proj.to_cols_array_2d(),
            eye: if facing { frame.eye.extend(1.0).to_array() } else { [0.0; 4] },
            first_receiver: at.first_receiver,
            receiver_count: at.vertex_count,
            generation,
            flags: VIEW_TEST | if facing { FACING_TEST } else { 0 } | if kernel.is_some() { KERNEL } else { 0 },
            sweep: sweep.map_or([0, 0], |s: Sweep| s.range(at.vertex_count)),
            reach: level.reach,
            stage: 0,
            kernel: kernel.map_or([0; 4], |t| [t.patches[0], t.patches[1], t.first_neighbour, t.vertices[0]]),
        })
    }
}

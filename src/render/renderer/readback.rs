//! Reading back what the last frames computed: the images, the exitance at the vertices, the
//! splat's irradiance at the samples, and where non-finite values are; and the one write of
//! exitance from the host (`set_exitance`).

use super::Renderer;
use crate::gpu::Access;
use crate::render::error::RenderError;
use crate::render::frame::{LevelExitance, NonFinite};
use crate::render::graph::{Resource, Resources, read};
use crate::render::local_exitance::LocalExitancePass;
use crate::render::pass::RenderPass;
use crate::render::plan::{Change, Pass, Plan, ReceiverScope, Sweep};
use ash::vk;

impl Renderer {
    /// The last tone-mapped image (RGBA8, rows top to bottom) and how many of its HDR pixels
    /// were non-finite (they are drawn black).
    pub fn image(&self) -> Result<(Vec<u8>, u32), RenderError> {
        let tonemap = self.passes.tonemap.as_ref().ok_or(RenderError::NoOwnImage)?;
        Ok(tonemap.read()?)
    }

    /// The last linear HDR image, RGBA f32, rows top to bottom.
    pub fn hdr_image(&self) -> Result<Vec<f32>, RenderError> {
        let hdr = self.targets.hdr().ok_or(RenderError::NoOwnImage)?;
        let mut hazards = self.hazards.borrow_mut();
        let bytes = hdr.read(hazards.last_access(Resource::Hdr))?;
        // The copy waited for the fence and left the image in TRANSFER_SRC.
        hazards.image(Resource::Hdr, hdr.raw(), vk::ImageAspectFlags::COLOR, Access::TransferRead);
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Radiant exitance (RGB, W/m^2 for the scene's light units) at every vertex of object
    /// `object`, from the last vertex gather (zero in pixel-gather mode).
    pub fn exitance(&self, object: usize) -> Result<Vec<[f32; 3]>, RenderError> {
        self.check_object(object)?;
        if self.planner.gathered_coarser(object) {
            return Err(RenderError::ExitanceAtCoarserLevel(object));
        }
        self.exitance_all(object)
    }

    /// Object `object`'s exitance as shading draws it, at every vertex: the gathered channels as
    /// [`Renderer::exitance`] reads them, and the channels the last recorded frame computed
    /// locally as `M = R_d,total E_t` at the vertex, with that frame's shadow maps and filter
    /// (`local_exitance` pass, recorded in a submission of its own and waited for). Call after a
    /// frame, with none in flight.
    pub fn exitance_drawn(&self, object: usize) -> Result<Vec<[f32; 3]>, RenderError> {
        let mut exitance = self.exitance(object)?;
        let mask = self.gpu_scene.local_channels(object);
        if mask == 0 {
            return Ok(exitance);
        }
        let resources = Resources { scene: &self.gpu_scene, targets: &self.targets };
        let pass = LocalExitancePass::new(&self.gpu, &resources, object)?;
        let plan = self.planner.plan_for(&self.needs, &self.view(), Change::Camera);
        self.record_alone("local exitance", &pass, &plan, Resource::LocalExitance)?;
        let local: Vec<[f32; 4]> = self.gpu_scene.buffers.local_exitance.read()?;
        let first = self.gpu_scene.object_range(object).first_vertex as usize;
        for (e, l) in exitance.iter_mut().zip(&local[first..]) {
            for c in (0..3).filter(|c| mask & (1 << c) != 0) {
                e[c] = l[c];
            }
        }
        Ok(exitance)
    }

    /// Object `object`'s exitance where the last gather computed it: the level of detail it
    /// gathered at, that level's vertices (object-relative, ascending) and their RGB exitance.
    /// Unlike [`Renderer::exitance`], it answers after a gather at a coarser level too.
    pub fn exitance_at_level(&self, object: usize) -> Result<LevelExitance, RenderError> {
        self.check_object(object)?;
        let level = self.planner.gathered_level(object).unwrap_or(0);
        let all = self.exitance_all(object)?;
        let vertices = match self.scene.objects[object].levels.get(level) {
            Some(l) if level > 0 => l.vertices.clone(),
            _ => (0..all.len() as u32).collect(),
        };
        let values = vertices.iter().map(|&v| all[v as usize]).collect();
        Ok(LevelExitance { level, vertices, values })
    }

    /// Object `object`'s exitance buffer as it stands, every vertex, after the receivers a
    /// visible-first gather left for later are gathered (`finish_sweep`).
    fn exitance_all(&self, object: usize) -> Result<Vec<[f32; 3]>, RenderError> {
        self.finish_sweep(object)?;
        let all: Vec<[f32; 4]> = self.gpu_scene.buffers.exitance.read()?;
        let first = self.gpu_scene.object_range(object).first_vertex as usize;
        let count = self.scene.objects[object].mesh.positions().len();
        Ok(all[first..first + count].iter().map(|e| [e[0], e[1], e[2]]).collect())
    }

    /// Gather, in a submission of its own, the receivers of object `object` that its last
    /// visible-first gather left for later frames (`plan::receivers`), at the level it gathered
    /// at: the whole level in one chunk, under the same splat generation, so that what is read
    /// back is what a gather of every receiver gives. The planner's sweep goes on, finding
    /// nothing left. Nothing when no sweep is pending.
    fn finish_sweep(&self, object: usize) -> Result<(), RenderError> {
        let Some(generation) = self.planner.sweep_pending(object) else { return Ok(()) };
        let Some(gather) = self.passes.get(Pass::Gather) else { return Ok(()) };
        let mut plan = self.planner.plan_for(&self.needs, &self.view(), Change::Camera);
        for o in &mut plan.objects {
            o.gather = o.object == object;
        }
        let o = &mut plan.objects[object];
        o.level = self.planner.gathered_level(object).unwrap_or(0);
        o.receivers = ReceiverScope::VisibleFirst { generation, fresh: false, sweep: Some(Sweep::ALL) };
        self.record_alone("finish sweep", gather, &plan, Resource::Exitance)
    }

    /// Record `pass` alone for `plan` in a submission of its own, wait, and leave its output `out`
    /// readable by the host (directly or by a copy).
    fn record_alone(&self, name: &str, pass: &dyn RenderPass, plan: &Plan, out: Resource) -> Result<(), RenderError> {
        self.gpu.one_shot(name, |cmd| {
            let frame = self.inputs(plan, None, None);
            frame.before(cmd, &pass.uses(&frame));
            pass.record(cmd, &frame);
            frame.before(cmd, &[read(out, Access::HostRead), read(out, Access::TransferRead)]);
        })?;
        Ok(())
    }

    /// Replace object `object`'s per-vertex exitance (RGB per vertex, its vertex order) before
    /// a frame that shades without gathering (`Change::Camera` in vertex mode): how the study
    /// draws the image of the exact exitance. The next gather overwrites it. Call with no
    /// frame in flight.
    pub fn set_exitance(&mut self, object: usize, exitance: &[[f32; 3]]) -> Result<(), RenderError> {
        self.check_object(object)?;
        let vertices = self.scene.objects[object].mesh.positions().len();
        if vertices != exitance.len() {
            return Err(RenderError::ExitanceCount { object, vertices, given: exitance.len() });
        }
        let first = u64::from(self.gpu_scene.object_range(object).first_vertex);
        let values: Vec<[f32; 4]> = exitance.iter().map(|e| [e[0], e[1], e[2], 1.0]).collect();
        self.gpu_scene.buffers.exitance.write(first * 16, &values)?;
        self.hazards.get_mut().written_outside(Resource::Exitance);
        self.planner.exitance_written(object);
        Ok(())
    }

    /// Splat output of every sample, in scene order: (irradiance RGB, area).
    pub fn splat_irradiance(&self) -> Result<Vec<([f32; 3], f32)>, RenderError> {
        Ok(self
            .splat_records()?
            .iter()
            .map(|s| ([s.irradiance_area[0], s.irradiance_area[1], s.irradiance_area[2]], s.irradiance_area[3]))
            .collect())
    }

    /// The splat's whole record of every sample, in scene order.
    pub fn splat_records(&self) -> Result<Vec<crate::render::records::SplatRecord>, RenderError> {
        // A scene without samples still has a buffer, of 16 bytes: less than one record.
        if self.scene.sample_count() == 0 {
            return Ok(Vec::new());
        }
        Ok(self.gpu_scene.buffers.splat.read()?)
    }

    /// Where the last frame's non-finite values are, pass by pass and object by object (the
    /// splat's irradiance at the samples, the gather's exitance at the vertices), so a NaN is
    /// reported with its cause instead of drawn black. Empty when both are finite: then a
    /// non-finite pixel comes from shading.
    pub fn find_non_finite(&self) -> Result<Vec<NonFinite>, RenderError> {
        let splat = self.splat_irradiance()?;
        let exitance: Vec<[f32; 4]> = self.gpu_scene.buffers.exitance.read()?;
        let mut found = Vec::new();
        let mut first_sample = 0;
        for (object, o) in self.scene.objects.iter().enumerate() {
            let samples = &splat[first_sample..first_sample + o.samples.len()];
            first_sample += o.samples.len();
            let bad = samples.iter().filter(|(e, a)| !(e.iter().all(|v| v.is_finite()) && a.is_finite())).count();
            if bad > 0 {
                found.push(NonFinite { pass: Pass::Splat, object, count: bad });
            }
            let first = self.gpu_scene.object_range(object).first_vertex as usize;
            let vertices = &exitance[first..first + o.mesh.positions().len()];
            let bad = vertices.iter().filter(|e| !e.iter().all(|v| v.is_finite())).count();
            if bad > 0 {
                found.push(NonFinite { pass: Pass::Gather, object, count: bad });
            }
        }
        Ok(found)
    }
}

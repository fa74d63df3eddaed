//! Editing the scene between frames: `edit` with a `SceneEdit` is the one way, each case
//! re-preparing only what it reaches; and baking opaque objects' levels of detail from their
//! sky light.

use super::{Renderer, SKY_LOCK_SHARE};
use crate::render::camera::CameraView;
use crate::render::edit::SceneEdit;
use crate::render::error::RenderError;
use crate::render::fit::check_fits;
use crate::render::gpu_scene::GpuScene;
use crate::render::graph::Resources;
use crate::render::pass::{PassContext, Rebuild};
use crate::render::plan::{Change, Planner};
use crate::render::target::TargetDesc;
use crate::render::targets::CameraTargets;
use crate::scene::Light;

impl Renderer {
    /// Apply one edit of the scene (`SceneEdit`), re-preparing only what it reaches; the next
    /// frame's plan redoes what it invalidates. The one way to change the scene a renderer draws.
    pub fn edit(&mut self, edit: SceneEdit) -> Result<(), RenderError> {
        match edit {
            SceneEdit::Camera(camera) => {
                self.set_camera(camera);
                Ok(())
            }
            SceneEdit::Resize { width, height } => self.resize(width, height),
            SceneEdit::Light { index, light } => self.set_light(index, light),
            SceneEdit::Material { object, material } => self.set_material(object, material),
            SceneEdit::Transform { object, transform } => self.set_transform(object, transform),
            SceneEdit::Scene(scene) => self.set_scene(*scene),
        }
    }

    /// Draw `scene` instead (`SceneEdit::Scene`): a renderer made for it, whose scene data,
    /// targets, passes, barrier records and planner replace this one's.
    fn set_scene(&mut self, scene: crate::scene::build::PreparedScene) -> Result<(), RenderError> {
        self.wait_for_recorded()?;
        let mut fresh = Renderer::with_options(&self.gpu, scene, self.target, self.options)?;
        // Swapped field by field: `fresh` then drops with what this renderer drew before.
        std::mem::swap(&mut self.passes, &mut fresh.passes);
        std::mem::swap(&mut self.targets, &mut fresh.targets);
        std::mem::swap(&mut self.gpu_scene, &mut fresh.gpu_scene);
        std::mem::swap(&mut self.hazards, &mut fresh.hazards);
        std::mem::swap(&mut self.needs, &mut fresh.needs);
        std::mem::swap(&mut self.planner, &mut fresh.planner);
        std::mem::swap(&mut self.scene, &mut fresh.scene);
        self.background = fresh.background;
        self.undo = None;
        Ok(())
    }

    /// Move the camera: the next frame re-shades (and, in pixel mode, gathers again); exitance
    /// at the vertices does not depend on the view.
    fn set_camera(&mut self, camera: CameraView) {
        self.camera = camera;
        self.planner.mark(Change::Camera);
    }

    /// Change the own target's size (the CLI's image): its images are made anew, and the passes
    /// that bind them (`Rebuild::Resize`). The camera's projection is the caller's
    /// (`SceneEdit::Camera`), for the new aspect ratio. A host target takes its extent from each
    /// frame's `HostTarget` instead.
    fn resize(&mut self, width: u32, height: u32) -> Result<(), RenderError> {
        if self.target != TargetDesc::Own {
            return Err(RenderError::ResizeHostTarget);
        }
        self.scene.scene.file.camera.resolution = [width, height];
        check_fits(&self.gpu, &self.scene)?;
        self.wait_for_recorded()?;
        let gpu = self.gpu.clone();
        // The old images' last frame must be done before they go (the caller's contract).
        self.targets.camera = Some(CameraTargets::new(&gpu, [width, height], self.needs.pixel_gather)?);
        let resources = Resources { scene: &self.gpu_scene, targets: &self.targets };
        let (scene, needs, options) = (&self.scene, &self.needs, &self.options);
        let context = PassContext { gpu: &gpu, resources, scene, needs, target: self.target, options };
        self.passes.rebuild(&context, Rebuild::Resize)?;
        self.targets.track_camera(self.hazards.get_mut());
        self.planner.mark(Change::Camera);
        Ok(())
    }

    /// Replace scene light `index` by `light` of the same kind (moved, re-aimed or re-coloured),
    /// and upload the lights' records and shadow matrices. Render the next frame with
    /// `Change::Light(index)`.
    fn set_light(&mut self, index: usize, light: Light) -> Result<(), RenderError> {
        let lights = &mut self.scene.scene.file.lights;
        match lights.get_mut(index) {
            Some(old) if std::mem::discriminant(old) == std::mem::discriminant(&light) => *old = light,
            _ => return Err(RenderError::LightKindChanged(index)),
        }
        self.scene.reprepare_lights();
        self.gpu_scene.set_lights(&self.scene);
        self.planner.mark(Change::Light(index));
        Ok(())
    }

    /// Replace object `object`'s translucent material (new coefficients, same samples): its
    /// record is re-packed and uploaded by the next frame, which reruns its splat and gather
    /// (`Change::Material`). Errors when the object is opaque or the index is out of range, and
    /// where its model takes single scattering between points before or after the edit (its
    /// tables are built with the scene).
    fn set_material(&mut self, object: usize, material: crate::optics::Material) -> Result<(), RenderError> {
        self.check_object(object)?;
        if self.gpu_scene.beams[object].is_some() {
            return Err(RenderError::MaterialWithBeamTables(object));
        }
        let target = self.scene.scene.file.render.max_error;
        let o = &mut self.scene.objects[object];
        let crate::scene::build::ResolvedMaterial::Translucent { material: m, dipoles, mm_per_unit, model, .. } =
            &mut o.material
        else {
            return Err(RenderError::OpaqueObject(object));
        };
        let edited =
            material.dipoles(*mm_per_unit).map_err(|source| RenderError::InvalidMaterial { object, source })?;
        // A channel the edit would give single scattering has no tables to take it from.
        if model.single_channels(edited.map(|d| d.alpha_prime)).contains(&true) {
            return Err(RenderError::MaterialWithBeamTables(object));
        }
        *dipoles = edited;
        // The one copy: the prepared object's. A later move (`SceneEdit::Transform`) keeps it,
        // and `scene().scene.file` stays the file as it was read.
        *m = material;
        o.choose_model(target);
        // The kernel is the old medium's: the object takes the dipole until one is attached.
        if o.transport.take().is_some() {
            o.kernel_dropped = Some(crate::scene::build::KernelDropped::MaterialEdited);
            self.gpu_scene.transport[object] = None;
        }
        self.gpu_scene.set_material(&self.scene, object);
        self.needs = Self::needs_of(&self.scene, self.target, &self.planner);
        self.planner.mark(Change::Material(object));
        Ok(())
    }

    /// Move object `object`: `transform` replaces its transform in the scene. That object alone
    /// is placed again and resampled (same method, count and seed), and the scene's GPU data
    /// and the passes that bind it are made anew (the hierarchy and its lists depend on the
    /// geometry); the frame targets, timers, camera and shadow pass stay. The next frame redraws
    /// every shadow and gathers every object (`Change::Geometry`). Call with no frame of this
    /// renderer in flight: its scene buffers are replaced. On an error nothing changed.
    fn set_transform(&mut self, object: usize, transform: crate::scene::Transform) -> Result<(), RenderError> {
        self.check_object(object)?;
        self.wait_for_recorded()?;
        let mut scene = self.scene.clone();
        scene.set_transform(object, transform)?;
        check_fits(&self.gpu, &scene)?;
        let old = std::mem::replace(&mut self.scene, scene);
        if let Err(e) = self.rebuild_scene_data() {
            self.scene = old;
            return Err(e);
        }
        // Every buffer is new: nothing is gathered yet, and the change covers what was pending.
        let pending = self.planner.pending().map_or(Change::Geometry(object), |p| p.and(Change::Geometry(object)));
        self.planner = Planner::new(self.scene.objects.len(), pending);
        self.needs = Self::needs_of(&self.scene, self.target, &self.planner);
        Ok(())
    }

    /// The scene's GPU data made anew from `self.scene`, and the passes that bind it
    /// (`Rebuild::SceneData`); the other passes, the frame targets, timers and camera stay. No
    /// frame may be in flight (the old buffers go).
    fn rebuild_scene_data(&mut self) -> Result<(), RenderError> {
        let gpu = self.gpu.clone();
        let gpu_scene = GpuScene::new(&gpu, &self.scene)?;
        let resources = Resources { scene: &gpu_scene, targets: &self.targets };
        let (scene, needs, options) = (&self.scene, &self.needs, &self.options);
        let context = PassContext { gpu: &gpu, resources, scene, needs, target: self.target, options };
        // Built first, then swapped in: an error leaves the renderer as it was.
        self.passes.rebuild(&context, Rebuild::SceneData)?;
        self.gpu_scene = gpu_scene;
        let hazards = self.hazards.get_mut();
        for &r in crate::render::graph::SCENE_BUFFERS {
            hazards.forget(r);
        }
        Ok(())
    }

    /// Bake the levels of detail of opaque objects under an environment light from their
    /// per-vertex sky light as the last vertex-light pass left it (read back): the vertices
    /// where it varies by more than `SKY_LOCK_SHARE` of the object's brightest are kept, the
    /// others simplified away like any mesh's (`mesh::Mesh::levels_of_detail_locked`). So a
    /// flat floor keeps its density only around the soft shadows on it. `frame` calls this
    /// after each frame that ran the vertex-light pass; a host recording its own frames calls
    /// it after the fence of such a frame, with no frame in flight (the index buffer is
    /// replaced). From the frame that recomputes the sky light until then, those objects are
    /// drawn whole (the planner withdraws their baked levels, `plan::BakedLevels`). Returns
    /// whether anything was baked.
    pub fn bake_static_levels(&mut self) -> Result<bool, RenderError> {
        if !self.scene.scene.file.render.level_of_detail || self.needs.environment.is_none() {
            return Ok(false);
        }
        self.wait_for_recorded()?;
        let sky: Vec<[f32; 4]> = self.gpu_scene.buffers.environment_irradiance.read()?;
        let mut baked = false;
        let mut first = 0;
        for o in &mut self.scene.objects {
            let count = o.mesh.positions().len();
            if matches!(o.material, crate::scene::build::ResolvedMaterial::Opaque { .. }) {
                let values: Vec<[f32; 3]> = sky[first..first + count].iter().map(|e| [e[0], e[1], e[2]]).collect();
                let locked = o.mesh.locks_where_varying(&values, SKY_LOCK_SHARE);
                o.levels = o.mesh.levels_of_detail_locked(&locked);
                baked = true;
            }
            first += count;
        }
        if baked {
            self.gpu_scene.set_levels(&self.gpu, &self.scene)?;
            self.planner.levels_baked();
            self.needs = Self::needs_of(&self.scene, self.target, &self.planner);
        }
        Ok(baked)
    }
}

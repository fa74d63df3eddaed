//! `Renderer`: the passes a prepared scene needs, built over its GPU data (`GpuScene`), and the
//! frame loop that records the passes a plan asks for, each timed with the `GpuTimer`. Outputs
//! stay on the GPU between frames, so a frame that skips a pass reuses its last result.

use super::gather::GatherPass;
use super::gather_pixel::GatherPixelPass;
use super::gather_sparse::GatherSparsePass;
use super::gpu_scene::GpuScene;
use super::pass::{FrameInputs, RenderPass};
use super::plan::{self, Change, Pass, Plan};
use super::shade::ShadePass;
use super::shadow::ShadowPass;
use super::splat::SplatPass;
use super::tonemap::TonemapPass;
use super::vertex_light::VertexLightPass;
use crate::gpu::{Access, Gpu, GpuError, GpuTimer, ShaderInterface};
use crate::scene::build::PreparedScene;
use crate::scene::needs::SceneNeeds;
use crate::scene::{GatherMode, Light};
use glam::Vec3;
use std::sync::Arc;

/// Why a renderer could not be made.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The scene asks for more than the device has.
    #[error("{setting} = {value} does not fit this device: its {limit_name} is {limit}")]
    DoesNotFit { setting: String, value: u64, limit_name: &'static str, limit: u64 },
    #[error("light {0} cannot be replaced by a light of another kind")]
    LightKindChanged(usize),
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// Non-finite values one pass left on one object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NonFinite {
    pub pass: &'static str,
    pub object: usize,
    /// Samples (splat) or vertices (gather) with a NaN or infinite value.
    pub count: usize,
}

/// Per-pass GPU milliseconds of one frame, in recording order.
#[derive(Clone, Debug, Default)]
pub struct FrameTimings {
    pub passes: Vec<(String, f64)>,
}

impl FrameTimings {
    pub fn total(&self) -> f64 {
        self.passes.iter().map(|(_, ms)| ms).sum()
    }
    pub fn get(&self, name: &str) -> Option<f64> {
        self.passes.iter().find(|(n, _)| n == name).map(|(_, ms)| *ms)
    }
}

pub struct Renderer {
    gpu: Arc<Gpu>,
    scene: PreparedScene,
    needs: SceneNeeds,
    // Passes drop before the data their descriptor sets point into.
    shadow: ShadowPass,
    vertex_light: VertexLightPass,
    splat: SplatPass,
    /// Vertex, sparse or pixel gather (`render.gather`).
    gather: Box<dyn RenderPass>,
    shade: ShadePass,
    tonemap: TonemapPass,
    timer: Option<GpuTimer>,
    buffers: GpuScene,
    background: [f32; 3],
}

impl Renderer {
    pub fn new(gpu: &Arc<Gpu>, scene: PreparedScene) -> Result<Renderer, RenderError> {
        check_fits(gpu, &scene)?;
        let buffers = GpuScene::new(gpu, &scene)?;
        let settings = &scene.scene.file.render;
        let shadow = ShadowPass::new(gpu, settings.shadow_map_size, scene.shadow_layers)?;
        let needs = scene.needs();
        let shade = ShadePass::new(gpu, scene.scene.file.camera.resolution, &buffers, &shadow, needs.pixel_gather)?;
        let gather: Box<dyn RenderPass> = match shade.surface() {
            Some(surface) => Box::new(GatherPixelPass::new(gpu, &buffers, surface, shade.hdr())?),
            None if settings.gather == GatherMode::Sparse => Box::new(GatherSparsePass::new(gpu, &buffers)?),
            None => Box::new(GatherPass::new(gpu, &buffers)?),
        };
        // Timing is optional: a queue without timestamps still renders.
        let timer = GpuTimer::new(gpu, 8).inspect_err(|e| log::warn!("no GPU timings: {e}")).ok();
        Ok(Renderer {
            gpu: gpu.clone(),
            vertex_light: VertexLightPass::new(gpu, &buffers, &shadow)?,
            splat: SplatPass::new(gpu, &buffers, &shadow)?,
            tonemap: TonemapPass::new(gpu, shade.hdr())?,
            shadow,
            gather,
            shade,
            timer,
            buffers,
            background: scene.background(),
            needs,
            scene,
        })
    }

    pub fn scene(&self) -> &PreparedScene {
        &self.scene
    }

    /// The scene's data on the GPU (for readback, or an engine binding it elsewhere).
    pub fn buffers(&self) -> &GpuScene {
        &self.buffers
    }

    /// The scene's data on the GPU, to write (a test feeding the gather its own input).
    pub fn buffers_mut(&mut self) -> &mut GpuScene {
        &mut self.buffers
    }

    /// The passes a frame with this change would run.
    pub fn plan(&self, change: Change) -> Plan {
        plan::plan(&self.needs, change)
    }

    fn pass(&self, pass: Pass) -> &dyn RenderPass {
        match pass {
            Pass::Shadow => &self.shadow,
            Pass::VertexLight => &self.vertex_light,
            Pass::Splat => &self.splat,
            Pass::Gather => self.gather.as_ref(),
            Pass::Shade => &self.shade,
            Pass::Tonemap => &self.tonemap,
        }
    }

    /// Record `passes` of `plan` into `cmd`, each between the timer's marks when given.
    fn record(&self, cmd: ash::vk::CommandBuffer, plan: &Plan, passes: &[Pass], mut timer: Option<&mut GpuTimer>) {
        let camera = &self.scene.scene.file.camera;
        let layers = plan.shadow_light.map(|source| self.scene.shadow_layers_of(source));
        let frame = FrameInputs {
            gpu: &self.gpu,
            scene: &self.buffers,
            plan,
            shadow_layers: layers.as_deref(),
            view_proj: camera.projection(self.scene.bounds.0, self.scene.bounds.1) * camera.view(),
            eye: Vec3::from(camera.eye),
            background: self.background,
            exposure: self.scene.scene.file.render.exposure,
        };
        for &pass in passes {
            if let Some(t) = timer.as_deref_mut() {
                t.begin(cmd, pass.name());
            }
            self.pass(pass).record(cmd, &frame);
            if let Some(t) = timer.as_deref_mut() {
                t.end(cmd);
            }
        }
    }

    /// Render one frame: record the passes of `plan` in one submission, wait, and return their
    /// GPU times from timestamp queries (none on a queue that cannot write timestamps).
    pub fn frame(&mut self, plan: &Plan) -> Result<FrameTimings, RenderError> {
        // Taken out for the recording, which borrows `self` immutably.
        let mut timer = self.timer.take();
        let passes: Vec<Pass> = plan.passes.iter().map(|(p, _)| *p).collect();
        let result = self.gpu.one_shot("frame", |cmd| {
            if let Some(t) = timer.as_mut() {
                t.reset(cmd);
            }
            self.record(cmd, plan, &passes, timer.as_mut());
        });
        let passes = result.and_then(|()| timer.as_ref().map_or(Ok(Vec::new()), GpuTimer::results));
        self.timer = timer;
        Ok(FrameTimings { passes: passes? })
    }

    /// Render one frame with every pass in a submission of its own, and return each pass's
    /// time from submission to fence (wall clock, milliseconds). Slower than `frame`, but on
    /// devices whose timestamps do not wait for compute work (lavapipe runs dispatches
    /// asynchronously), this is the figure that bounds each pass.
    pub fn frame_isolated(&mut self, plan: &Plan) -> Result<FrameTimings, RenderError> {
        let mut passes = Vec::new();
        for (pass, _) in &plan.passes {
            let start = std::time::Instant::now();
            self.gpu.one_shot(pass.name(), |cmd| self.record(cmd, plan, &[*pass], None))?;
            passes.push((pass.name().to_string(), start.elapsed().as_secs_f64() * 1e3));
        }
        Ok(FrameTimings { passes })
    }

    /// The last tone-mapped image (RGBA8, rows top to bottom) and how many of its HDR pixels
    /// were non-finite (they are drawn black).
    pub fn image(&self) -> Result<(Vec<u8>, u32), RenderError> {
        Ok(self.tonemap.read()?)
    }

    /// The last linear HDR image, RGBA f32, rows top to bottom.
    pub fn hdr_image(&self) -> Result<Vec<f32>, RenderError> {
        let bytes = self.shade.hdr().read(Access::ComputeSampledRead)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Radiant exitance (RGB, W/m^2 for the scene's light units) at every vertex of object
    /// `object`, from the last vertex gather (zero in pixel-gather mode).
    pub fn exitance(&self, object: usize) -> Result<Vec<[f32; 3]>, RenderError> {
        let all: Vec<[f32; 4]> = self.buffers.exitance.read()?;
        let first = self.buffers.vertex_offsets[object] as usize;
        let count = self.scene.objects[object].mesh.positions().len();
        Ok(all[first..first + count].iter().map(|e| [e[0], e[1], e[2]]).collect())
    }

    /// Splat output of every sample, in scene order: (irradiance RGB, area).
    pub fn splat_irradiance(&self) -> Result<Vec<([f32; 3], f32)>, RenderError> {
        let all: Vec<super::records::SplatRecord> = self.buffers.splat.read()?;
        Ok(all
            .iter()
            .map(|s| ([s.irradiance_area[0], s.irradiance_area[1], s.irradiance_area[2]], s.irradiance_area[3]))
            .collect())
    }

    /// Replace scene light `index` by `light` of the same kind (moved, re-aimed or re-coloured),
    /// and upload the lights' records and shadow matrices. Render the next frame with
    /// `Change::Light(index)`.
    pub fn set_light(&mut self, index: usize, light: Light) -> Result<(), RenderError> {
        let lights = &mut self.scene.scene.file.lights;
        match lights.get_mut(index) {
            Some(old) if std::mem::discriminant(old) == std::mem::discriminant(&light) => *old = light,
            _ => return Err(RenderError::LightKindChanged(index)),
        }
        self.scene.reprepare_lights();
        Ok(self.buffers.upload_lights(&self.scene)?)
    }

    /// Where the last frame's non-finite values are, pass by pass and object by object (the
    /// splat's irradiance at the samples, the gather's exitance at the vertices), so a NaN is
    /// reported with its cause instead of drawn black. Empty when both are finite: then a
    /// non-finite pixel comes from shading.
    pub fn find_non_finite(&self) -> Result<Vec<NonFinite>, RenderError> {
        let splat = self.splat_irradiance()?;
        let exitance: Vec<[f32; 4]> = self.buffers.exitance.read()?;
        let mut found = Vec::new();
        let mut first_sample = 0;
        for (object, o) in self.scene.objects.iter().enumerate() {
            let samples = &splat[first_sample..first_sample + o.samples.len()];
            first_sample += o.samples.len();
            let bad = samples.iter().filter(|(e, a)| !(e.iter().all(|v| v.is_finite()) && a.is_finite())).count();
            if bad > 0 {
                found.push(NonFinite { pass: "splat", object, count: bad });
            }
            let first = self.buffers.vertex_offsets[object] as usize;
            let vertices = &exitance[first..first + o.mesh.positions().len()];
            let bad = vertices.iter().filter(|e| !e.iter().all(|v| v.is_finite())).count();
            if bad > 0 {
                found.push(NonFinite { pass: "gather", object, count: bad });
            }
        }
        Ok(found)
    }

    /// Bytes of device memory in use by the allocator.
    pub fn device_memory(&self) -> u64 {
        self.gpu.memory_usage().0
    }
}

/// An error naming the scene setting when the scene needs more than the device allows, before
/// any GPU work: dispatch sizes, image sizes and layers, storage-buffer ranges, and memory (the
/// largest single allocation against `maxMemoryAllocationSize`, the total against the largest
/// device-local heap).
fn check_fits(gpu: &Gpu, scene: &PreparedScene) -> Result<(), RenderError> {
    let limits = &gpu.properties().limits;
    // Vertex- and sample-wide passes dispatch along x only.
    let dispatchable = |shader: &str| -> Result<u64, RenderError> {
        Ok(limits.max_compute_work_group_count[0] as u64 * ShaderInterface::of(shader)?.local_size[0] as u64)
    };
    let dispatch = "maxComputeWorkGroupCount x local size";
    let image_side = limits.max_image_dimension2_d as u64;
    let file = &scene.scene.file;
    let [width, height] = file.camera.resolution.map(u64::from);
    let pixels = width * height;
    let (map, layers) = (file.render.shadow_map_size as u64, scene.shadow_layers.max(1) as u64);
    let (max_allocation, heap) = memory_limits(gpu);
    // The HDR image (and the surface image of the pixel gather), 16 bytes a pixel, and the
    // shadow-map array, 2 bytes a texel, are the large allocations; the rest is counted whole.
    let hdr_bytes = 16 * pixels;
    let shadow_bytes = 2 * map * map * layers;
    let vertex_bytes = 56 * scene.vertex_count() as u64 + 64 * scene.sample_count() as u64;
    let surface = if file.render.gather == GatherMode::Pixel { hdr_bytes } else { 0 };
    // HDR, surface, depth (4), tone-mapped output (4) and the EXR readback (16) per pixel.
    let total = hdr_bytes + surface + 24 * pixels + shadow_bytes + vertex_bytes;
    let checks = [
        (
            "the meshes' vertex count".to_string(),
            scene.vertex_count() as u64,
            dispatch,
            dispatchable("vertex_light.comp")?,
        ),
        (
            "sampling.count x translucent objects".into(),
            scene.sample_count() as u64,
            dispatch,
            dispatchable("splat.comp")?,
        ),
        ("camera.resolution (largest side)".into(), width.max(height), "maxImageDimension2D", image_side),
        (
            "camera.resolution (width x height x 4 bytes of tone-mapped output)".into(),
            4 * pixels,
            "maxStorageBufferRange",
            limits.max_storage_buffer_range as u64,
        ),
        ("render.shadow_map_size".into(), map, "maxImageDimension2D", image_side),
        (
            "shadow maps (one per shadow-casting light, environment directions included)".into(),
            scene.shadow_layers as u64,
            "maxImageArrayLayers",
            limits.max_image_array_layers as u64,
        ),
        (
            format!("bytes of the HDR image at camera.resolution {width}x{height}"),
            hdr_bytes,
            "maxMemoryAllocationSize",
            max_allocation,
        ),
        (
            format!("bytes of {layers} shadow maps of render.shadow_map_size {map}"),
            shadow_bytes,
            "maxMemoryAllocationSize",
            max_allocation,
        ),
        (
            format!(
                "bytes of device memory the scene needs (images at camera.resolution {width}x{height}, {layers} \
                 shadow maps of {map}^2, meshes and samples)"
            ),
            total,
            "largest device-local memory heap",
            heap,
        ),
    ];
    for (setting, value, limit_name, limit) in checks {
        if value > limit {
            return Err(RenderError::DoesNotFit { setting, value, limit_name, limit });
        }
    }
    Ok(())
}

/// `maxMemoryAllocationSize` and the size of the largest device-local heap.
fn memory_limits(gpu: &Gpu) -> (u64, u64) {
    let mut maintenance3 = ash::vk::PhysicalDeviceMaintenance3Properties::default();
    let mut properties = ash::vk::PhysicalDeviceProperties2::default().push_next(&mut maintenance3);
    // SAFETY: plain queries on the device in use (Vulkan 1.1 core).
    let memory = unsafe {
        gpu.instance().get_physical_device_properties2(gpu.physical_device(), &mut properties);
        gpu.instance().get_physical_device_memory_properties(gpu.physical_device())
    };
    let heaps = &memory.memory_heaps[..memory.memory_heap_count as usize];
    let local = heaps.iter().filter(|h| h.flags.contains(ash::vk::MemoryHeapFlags::DEVICE_LOCAL));
    (maintenance3.max_memory_allocation_size, local.map(|h| h.size).max().unwrap_or(u64::MAX))
}

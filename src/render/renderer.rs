//! `Renderer`: a prepared scene's GPU resources and the frame loop that records the passes a
//! plan asks for, each timed with the `GpuTimer`. Outputs stay on the GPU between frames, so a
//! frame that skips a pass reuses its last result.

use super::gather::GatherPass;
use super::gather_pixel::GatherPixelPass;
use super::gather_sparse::GatherSparsePass;
use super::plan::{self, Change, Pass, Plan, SceneNeeds};
use super::records::{MATERIAL_OPAQUE, MATERIAL_TRANSLUCENT, ObjectRecord, SampleRecord, Vertex};
use super::shade::{ShadePass, ShadePush};
use super::shadow::{DrawRange, ShadowPass};
use super::splat::{SPLAT_STRIDE, SplatPass};
use super::tonemap::TonemapPass;
use super::vertex_light::VertexLightPass;
use crate::gpu::{Buffer, BufferDesc, Gpu, GpuResult, GpuTimer, memory_barrier};
use crate::optics::fresnel;
use crate::optics::gpu::DipoleChannelGpu;
use crate::scene::build::{PreparedScene, ResolvedMaterial};
use crate::scene::lights::LightGpu;
use ash::vk;
use glam::Vec3;
use std::sync::Arc;

/// Where exitance is gathered (`render.gather`).
enum Gather {
    /// At every vertex of the translucent objects, interpolated by the shading pass.
    Vertex(GatherPass),
    /// At every pixel showing a translucent object, after the shading pass.
    Pixel(GatherPixelPass),
    /// At the sample points, blended to the vertices.
    Sparse(GatherSparsePass),
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
    vertices: Buffer,
    indices: Buffer,
    exitance: Buffer,
    environment_irradiance: Buffer,
    _objects: Buffer,
    _samples: Buffer,
    splat_buffer: Buffer,
    lights: Buffer,
    shadow: ShadowPass,
    vertex_light: VertexLightPass,
    splat: SplatPass,
    gather: Gather,
    shade: ShadePass,
    tonemap: TonemapPass,
    timer: Option<GpuTimer>,
    draws: Vec<DrawRange>,
    casters: Vec<DrawRange>,
    light_matrices: Vec<[[f32; 4]; 4]>,
    light_count: u32,
    /// First vertex of each object in the shared buffers.
    vertex_offsets: Vec<u32>,
    background: [f32; 3],
}

fn storage(gpu: &Arc<Gpu>, name: &str, bytes: u64, extra: vk::BufferUsageFlags) -> GpuResult<Buffer> {
    Buffer::new(gpu, &BufferDesc::gpu_only(name, bytes.max(16), vk::BufferUsageFlags::STORAGE_BUFFER | extra))
}

fn upload<T: bytemuck::Pod>(gpu: &Arc<Gpu>, name: &str, data: &[T], usage: vk::BufferUsageFlags) -> GpuResult<Buffer> {
    let bytes = std::mem::size_of_val(data) as u64;
    let mut buffer = storage(gpu, name, bytes, usage)?;
    if bytes > 0 {
        buffer.write(0, data)?;
    }
    Ok(buffer)
}

impl Renderer {
    pub fn new(gpu: &Arc<Gpu>, scene: PreparedScene) -> GpuResult<Renderer> {
        let mut vertices = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut objects = Vec::new();
        let mut samples = Vec::new();
        let mut draws = Vec::new();
        let mut casters = Vec::new();
        let mut vertex_offsets = Vec::new();
        let mut receivers = Vec::new();
        for (i, o) in scene.objects.iter().enumerate() {
            let first_vertex = vertices.len() as u32;
            let first_sample = samples.len() as u32;
            vertex_offsets.push(first_vertex);
            for (p, n) in o.mesh.positions().iter().zip(o.mesh.vertex_normals()) {
                vertices.push(Vertex { position: p.to_array(), normal: n.to_array() });
            }
            let draw = DrawRange {
                first_index: indices.len() as u32,
                index_count: 3 * o.mesh.triangles().len() as u32,
                vertex_offset: first_vertex as i32,
            };
            indices.extend(o.mesh.triangles().iter().flatten());
            draws.push(draw);
            if o.casts_shadow {
                casters.push(draw);
            }
            for s in &o.samples {
                samples.push(SampleRecord {
                    position_area: [s.position.x, s.position.y, s.position.z, s.area as f32],
                    normal_object: [s.normal.x, s.normal.y, s.normal.z, i as f32],
                });
            }
            let vertex_count = o.mesh.positions().len() as u32;
            let ranges = [first_vertex, vertex_count, first_sample, o.samples.len() as u32];
            objects.push(match &o.material {
                ResolvedMaterial::Translucent { material, dipoles, roughness, .. } => {
                    receivers.push((i as u32, vertex_count));
                    let t_eta = fresnel::diffuse_transmittance(material.eta);
                    let channel = |c: usize| {
                        let d = DipoleChannelGpu::from(&dipoles[c]);
                        [d.alpha_prime, d.sigma_tr, d.z_r, d.z_v]
                    };
                    ObjectRecord {
                        albedo_roughness: [0.0, 0.0, 0.0, *roughness],
                        eta_norm_kind: [
                            material.eta as f32,
                            (1.0 / (std::f64::consts::PI * t_eta)) as f32,
                            MATERIAL_TRANSLUCENT,
                            0.0,
                        ],
                        dipole: [channel(0), channel(1), channel(2)],
                        ranges,
                    }
                }
                ResolvedMaterial::Opaque { albedo, roughness } => ObjectRecord {
                    albedo_roughness: [albedo[0], albedo[1], albedo[2], *roughness],
                    eta_norm_kind: [1.5, 0.0, MATERIAL_OPAQUE, 0.0],
                    dipole: [[0.0; 4]; 3],
                    ranges,
                },
            });
        }
        let lights: Vec<LightGpu> = scene.lights.iter().map(|l| l.record).collect();
        let mut light_matrices = vec![[[0.0; 4]; 4]; scene.shadow_layers as usize];
        for l in &lights {
            if l.power_layer[3] >= 0.0 {
                light_matrices[l.power_layer[3] as usize] = l.shadow_matrix;
            }
        }
        // The vertex-wide and sample-wide passes dispatch one workgroup of 64 per 64 items in x.
        let max_groups = gpu.properties().limits.max_compute_work_group_count[0] as usize;
        for (what, count) in [("vertices", vertices.len()), ("sample points", samples.len())] {
            if count.div_ceil(64) > max_groups {
                return Err(crate::gpu::GpuError::Invalid(format!(
                    "the scene has {count} {what}; this device dispatches at most {} (64 x {max_groups})",
                    64 * max_groups
                )));
            }
        }
        let vertex_buffer = upload(gpu, "vertices", &vertices, vk::BufferUsageFlags::VERTEX_BUFFER)?;
        let index_buffer = upload(gpu, "indices", &indices, vk::BufferUsageFlags::INDEX_BUFFER)?;
        // Opaque vertices keep zero exitance; translucent ones are written by the gather.
        let exitance = upload(gpu, "exitance", &vec![[0f32; 4]; vertices.len()], vk::BufferUsageFlags::VERTEX_BUFFER)?;
        let environment_irradiance = upload(
            gpu,
            "environment irradiance",
            &vec![[0f32; 4]; vertices.len()],
            vk::BufferUsageFlags::VERTEX_BUFFER,
        )?;
        let object_buffer = upload(gpu, "objects", &objects, vk::BufferUsageFlags::empty())?;
        let sample_buffer = upload(gpu, "samples", &samples, vk::BufferUsageFlags::empty())?;
        let splat_buffer = storage(gpu, "splat", SPLAT_STRIDE * samples.len() as u64, vk::BufferUsageFlags::empty())?;
        let light_buffer = upload(gpu, "lights", &lights, vk::BufferUsageFlags::empty())?;

        let settings = &scene.scene.file.render;
        let shadow = ShadowPass::new(gpu, settings.shadow_map_size, scene.shadow_layers)?;
        let light_count = lights.len() as u32;
        let vertex_light = VertexLightPass::new(
            gpu,
            &vertex_buffer,
            vertices.len() as u32,
            &light_buffer,
            light_count,
            &shadow,
            &environment_irradiance,
        )?;
        let splat = SplatPass::new(
            gpu,
            &sample_buffer,
            samples.len() as u32,
            &object_buffer,
            &light_buffer,
            light_count,
            &shadow,
            &splat_buffer,
        )?;
        let [width, height] = scene.scene.file.camera.resolution;
        let pixel_gather = settings.gather == crate::scene::GatherMode::Pixel;
        let shade = ShadePass::new(gpu, width, height, &object_buffer, &light_buffer, &shadow, pixel_gather)?;
        let sparse_receivers: Vec<(u32, u32, u32)> = receivers
            .iter()
            .map(|&(object, vertex_count)| (object, vertex_count, scene.objects[object as usize].samples.len() as u32))
            .collect();
        let gather = match shade.surface() {
            None if settings.gather == crate::scene::GatherMode::Sparse => Gather::Sparse(GatherSparsePass::new(
                gpu,
                &vertex_buffer,
                &sample_buffer,
                samples.len() as u32,
                &splat_buffer,
                &object_buffer,
                &exitance,
                sparse_receivers,
            )?),
            Some(surface) => Gather::Pixel(GatherPixelPass::new(
                gpu,
                surface,
                &sample_buffer,
                &splat_buffer,
                &object_buffer,
                shade.hdr(),
            )?),
            None => Gather::Vertex(GatherPass::new(
                gpu,
                &vertex_buffer,
                &sample_buffer,
                &splat_buffer,
                &object_buffer,
                &exitance,
                receivers,
            )?),
        };
        let tonemap = TonemapPass::new(gpu, shade.hdr())?;
        // Timing is optional: a queue without timestamps still renders.
        let timer = match GpuTimer::new(gpu, 8) {
            Ok(t) => Some(t),
            Err(e) => {
                log::warn!("no GPU timings: {e}");
                None
            }
        };
        let background = settings.background.unwrap_or_else(|| match &scene.environment {
            // The sky's radiance near the horizon, as a backdrop.
            Some(env) => {
                let scale = scene
                    .scene
                    .file
                    .lights
                    .iter()
                    .find_map(|l| match l {
                        crate::scene::Light::Environment { scale, .. } => Some(*scale),
                        _ => None,
                    })
                    .unwrap_or(1.0);
                let row = env.height / 2 - 1;
                let sum: Vec3 = env.radiance[row * env.width..(row + 1) * env.width].iter().sum();
                (sum / env.width as f32 * scale).to_array()
            }
            None => [0.0; 3],
        });
        let mut shadowed_lights: Vec<usize> =
            scene.lights.iter().filter(|l| l.record.power_layer[3] >= 0.0).map(|l| l.source).collect();
        shadowed_lights.dedup();
        let needs = SceneNeeds {
            shadow_layers: scene.shadow_layers,
            translucent_objects: scene.objects.iter().filter(|o| !o.samples.is_empty()).count(),
            shadowed_lights,
            environment: scene.lights.iter().find(|l| l.record.spot_texel[3] > 0.5).map(|l| l.source),
            pixel_gather: settings.gather == crate::scene::GatherMode::Pixel,
        };
        Ok(Renderer {
            gpu: gpu.clone(),
            scene,
            needs,
            vertices: vertex_buffer,
            indices: index_buffer,
            exitance,
            environment_irradiance,
            _objects: object_buffer,
            _samples: sample_buffer,
            splat_buffer,
            lights: light_buffer,
            shadow,
            vertex_light,
            splat,
            gather,
            shade,
            tonemap,
            timer,
            draws,
            casters,
            light_matrices,
            light_count,
            vertex_offsets,
            background,
        })
    }

    pub fn scene(&self) -> &PreparedScene {
        &self.scene
    }

    /// The passes a frame with this change would run.
    pub fn plan(&self, change: Change) -> Plan {
        plan::plan(&self.needs, change)
    }

    /// Render one frame: record the passes of `plan` in one submission, wait, and return their
    /// GPU times from timestamp queries (none on a queue that cannot write timestamps).
    pub fn frame(&mut self, plan: &Plan) -> GpuResult<FrameTimings> {
        let gpu = self.gpu.clone();
        // Taken out for the recording, which borrows `self` immutably.
        let mut timer = self.timer.take();
        let result = gpu.one_shot("frame", |cmd| {
            if let Some(t) = timer.as_mut() {
                t.reset(cmd);
            }
            for (pass, _) in &plan.passes {
                if let Some(t) = timer.as_mut() {
                    t.begin(cmd, pass.name());
                }
                self.record_pass(cmd, plan, *pass);
                if let Some(t) = timer.as_mut() {
                    t.end(cmd);
                }
            }
        });
        let passes = result.and_then(|()| timer.as_ref().map_or(Ok(Vec::new()), GpuTimer::results));
        self.timer = timer;
        Ok(FrameTimings { passes: passes? })
    }

    /// Render one frame with every pass in a submission of its own, and return each pass's
    /// time from submission to fence (wall clock, milliseconds). Slower than `frame`, but on
    /// devices whose timestamps do not wait for compute work (lavapipe runs dispatches
    /// asynchronously), this is the figure that bounds each pass.
    pub fn frame_isolated(&mut self, plan: &Plan) -> GpuResult<FrameTimings> {
        let gpu = self.gpu.clone();
        let mut passes = Vec::new();
        for (pass, _) in &plan.passes {
            let start = std::time::Instant::now();
            gpu.one_shot(pass.name(), |cmd| self.record_pass(cmd, plan, *pass))?;
            passes.push((pass.name().to_string(), start.elapsed().as_secs_f64() * 1e3));
        }
        Ok(FrameTimings { passes })
    }

    /// Record one pass, followed by the barrier that makes its writes visible to the passes
    /// (and host reads) after it.
    fn record_pass(&self, cmd: vk::CommandBuffer, plan: &Plan, pass: Pass) {
        let gpu = &self.gpu;
        let device = gpu.device();
        let compute_writes = (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE);
        match pass {
            Pass::Shadow => {
                let only: Option<Vec<u32>> = plan.shadow_light.map(|source| {
                    let lights = self.scene.lights.iter().filter(|l| l.source == source);
                    lights.filter(|l| l.record.power_layer[3] >= 0.0).map(|l| l.record.power_layer[3] as u32).collect()
                });
                self.shadow.record(
                    gpu,
                    cmd,
                    &self.vertices,
                    &self.indices,
                    &self.casters,
                    &self.light_matrices,
                    only.as_deref(),
                )
            }
            Pass::VertexLight => {
                self.vertex_light.record(cmd);
                memory_barrier(
                    device,
                    cmd,
                    compute_writes,
                    (vk::PipelineStageFlags2::VERTEX_ATTRIBUTE_INPUT, vk::AccessFlags2::VERTEX_ATTRIBUTE_READ),
                );
            }
            Pass::Splat => {
                self.splat.record(cmd);
                memory_barrier(
                    device,
                    cmd,
                    compute_writes,
                    (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_READ),
                );
            }
            Pass::Gather => {
                match &self.gather {
                    Gather::Vertex(pass) => pass.record(cmd),
                    Gather::Pixel(pass) => pass.record(gpu, cmd),
                    Gather::Sparse(pass) => pass.record(gpu, cmd),
                }
                memory_barrier(
                    device,
                    cmd,
                    compute_writes,
                    (
                        vk::PipelineStageFlags2::VERTEX_ATTRIBUTE_INPUT | vk::PipelineStageFlags2::HOST,
                        vk::AccessFlags2::VERTEX_ATTRIBUTE_READ | vk::AccessFlags2::HOST_READ,
                    ),
                );
            }
            Pass::Shade => {
                let camera = &self.scene.scene.file.camera;
                let view_proj = camera.projection(self.scene.bounds.0, self.scene.bounds.1) * camera.view();
                let push = ShadePush {
                    view_proj: view_proj.to_cols_array_2d(),
                    eye_object: [camera.eye[0], camera.eye[1], camera.eye[2], 0.0],
                    counts: [self.light_count, crate::scene::lights::key_light_count(&self.scene.lights) as u32, 0, 0],
                };
                self.shade.record(
                    gpu,
                    cmd,
                    &self.vertices,
                    &self.exitance,
                    &self.environment_irradiance,
                    &self.indices,
                    &self.draws,
                    push,
                    self.background,
                );
            }
            Pass::Tonemap => {
                self.tonemap.record(gpu, cmd, self.scene.scene.file.render.exposure);
                memory_barrier(
                    device,
                    cmd,
                    compute_writes,
                    (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
                );
            }
        }
    }

    /// The last tone-mapped image (RGBA8, rows top to bottom) and how many of its HDR pixels
    /// were non-finite (they are drawn black).
    pub fn image(&self) -> GpuResult<(Vec<u8>, u32)> {
        self.tonemap.read()
    }

    /// The last linear HDR image, RGBA f32, rows top to bottom.
    pub fn hdr_image(&self) -> GpuResult<Vec<f32>> {
        let bytes = self.shade.hdr().read(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Radiant exitance (RGB, W/m^2 for the scene's light units) at every vertex of object
    /// `object`, from the last vertex gather (zero in pixel-gather mode).
    pub fn exitance(&self, object: usize) -> GpuResult<Vec<[f32; 3]>> {
        let all: Vec<[f32; 4]> = self.exitance.read()?;
        let first = self.vertex_offsets[object] as usize;
        let count = self.scene.objects[object].mesh.positions().len();
        Ok(all[first..first + count].iter().map(|e| [e[0], e[1], e[2]]).collect())
    }

    /// Splat output of every sample, in scene order: (irradiance RGB, area).
    pub fn splat_irradiance(&self) -> GpuResult<Vec<([f32; 3], f32)>> {
        let all: Vec<[f32; 4]> = self.splat_buffer.read()?;
        Ok(all.chunks(2).map(|c| ([c[0][0], c[0][1], c[0][2]], c[0][3])).collect())
    }

    /// Replace the splat output (irradiance RGB per sample, scene order) and recompute the near
    /// energies on the CPU, so a test can feed the gather the same input as the reference.
    pub fn set_splat_irradiance(&mut self, irradiance: &[[f32; 3]]) -> GpuResult<()> {
        let mut data = Vec::with_capacity(2 * irradiance.len());
        let mut k = 0;
        for o in &self.scene.objects {
            for s in &o.samples {
                let e = irradiance[k];
                data.push([e[0], e[1], e[2], s.area as f32]);
                let near = match &o.material {
                    ResolvedMaterial::Translucent { dipoles, .. } => {
                        let b = crate::optics::kernel::B_PER_SQRT_AREA * s.area.sqrt();
                        [0, 1, 2].map(|c| crate::optics::kernel::near_energy(&dipoles[c], b) as f32)
                    }
                    ResolvedMaterial::Opaque { .. } => [0.0; 3],
                };
                data.push([near[0], near[1], near[2], 0.0]);
                k += 1;
            }
        }
        self.splat_buffer.write(0, &data)
    }

    /// Turn scene light `index` (directional, point or spot) by `degrees` about the vertical
    /// axis through the scene's centre, and upload its new record and shadow matrix. Render the
    /// next frame with `Change::Light(index)`.
    pub fn orbit_light(&mut self, index: usize, degrees: f32) -> GpuResult<()> {
        let centre = self.scene.bounds.0;
        let rotation = glam::Quat::from_rotation_y(degrees.to_radians());
        let turn = |v: [f32; 3]| (rotation * Vec3::from(v)).to_array();
        let turn_point = |p: [f32; 3]| (centre + rotation * (Vec3::from(p) - centre)).to_array();
        let lights = &mut self.scene.scene.file.lights;
        match lights.get_mut(index) {
            Some(crate::scene::Light::Directional { direction, .. }) => *direction = turn(*direction),
            Some(crate::scene::Light::Point { position, .. }) => *position = turn_point(*position),
            Some(crate::scene::Light::Spot { position, direction, .. }) => {
                *position = turn_point(*position);
                *direction = turn(*direction);
            }
            _ => return Err(crate::gpu::GpuError::Invalid(format!("light {index} cannot be moved"))),
        }
        self.scene.reprepare_lights();
        for l in &self.scene.lights {
            let layer = l.record.power_layer[3];
            if layer >= 0.0 {
                self.light_matrices[layer as usize] = l.record.shadow_matrix;
            }
        }
        let records: Vec<LightGpu> = self.scene.lights.iter().map(|l| l.record).collect();
        self.lights.write(0, &records)
    }

    /// Bytes of device memory in use by the allocator.
    pub fn device_memory(&self) -> u64 {
        self.gpu.memory_usage().0
    }
}

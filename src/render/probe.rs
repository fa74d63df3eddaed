//! Probe pass (`glsl/test/probe.comp`), a test's pass: `local_exitance = 2 exitance` at every
//! vertex. It exists to show, and to test, what a new pass takes: this module, its GLSL file
//! and one line in `registry::for_each_pass!`. Nothing else names it: the planner's `Pass`, the
//! renderer's table of passes, its construction and its rebuilds all follow from that line.
//! No plan the planner makes runs it; the test records it with a plan of its own.
//!
//! Bindings: 0 = exitance (read), 1 = local exitance (written). Push: the vertex count.

use super::error::RenderError;
use super::graph::{Resource, Use, compute_uses};
use super::pass::{FrameInputs, PassContext, Rebuild, RegisteredPass, RenderPass};
use crate::gpu::{ComputePipeline, DescriptorSet};
use ash::vk;

/// glsl/test/probe.comp's bindings, in binding order.
const BINDINGS: [Resource; 2] = [Resource::Exitance, Resource::LocalExitance];

/// One dispatch over every vertex of the scene.
pub struct ProbePass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
}

impl RenderPass for ProbePass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        compute_uses(&BINDINGS, &[Resource::LocalExitance])
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let count = frame.scene.vertex_count;
        self.pipeline.dispatch(cmd, &self.set, &count, [count, 1, 1]);
    }
}

impl RegisteredPass for ProbePass {
    // It binds two scene buffers, which a new transform makes anew.
    const REBUILT_ON: &'static [Rebuild] = &[Rebuild::SceneData];

    fn build(context: &PassContext) -> Result<Option<Self>, RenderError> {
        let pipeline = ComputePipeline::new(context.gpu, "test/probe.comp")?;
        let set = pipeline.descriptor_set(&context.resources.bind_all(&BINDINGS)?)?;
        Ok(Some(ProbePass { pipeline, set }))
    }
}

#[cfg(test)]
mod tests {
    use crate::gpu::{Gpu, GpuOptions};
    use crate::render::plan::{Change, Pass, PassReason, Plan};
    use crate::render::renderer::Renderer;
    use crate::scene::Scene;
    use crate::scene::build::{Overrides, PreparedScene};

    #[test]
    fn a_pass_registered_by_one_line_runs_after_the_gather_and_doubles_its_exitance() {
        let options =
            GpuOptions { device: std::env::var("TRANSLUCENT_DEVICE").ok(), validation: true, ..GpuOptions::default() };
        let gpu = Gpu::new(&options).unwrap_or_else(|e| {
            panic!("GPU tests need a Vulkan device with validation layers: {e}\nrun `bash scripts/setup`")
        });
        let counters = gpu.validation();
        {
            let mut builtin = Scene::builtin();
            builtin.file.camera.resolution = [64, 64];
            let scene = PreparedScene::new(&builtin, &Overrides::default()).unwrap();
            let mut renderer = Renderer::new(&gpu, scene).unwrap();
            let full = renderer.plan(Change::Everything);
            renderer.frame(&full).unwrap();
            let probe = Plan {
                passes: vec![(Pass::Probe, PassReason::ExitanceStale { objects: vec![] })],
                skipped: Vec::new(),
                ..full
            };
            let timings = renderer.frame(&probe).unwrap();
            assert_eq!(timings.passes.iter().map(|p| p.0).collect::<Vec<_>>(), [Pass::Probe]);
            let data = renderer.scene_data();
            let exitance: Vec<[f32; 4]> = data.buffers.exitance.read().unwrap();
            let doubled: Vec<[f32; 4]> = data.buffers.local_exitance.read().unwrap();
            assert!(exitance.iter().any(|e| e[0] > 0.0), "the gather left no exitance to probe");
            for (v, (e, d)) in exitance.iter().zip(&doubled).enumerate() {
                assert_eq!(e.map(|x| 2.0 * x), *d, "vertex {v}");
            }
        }
        drop(gpu);
        assert_eq!(counters.total(), 0, "validation: {}", counters.messages().join("\n"));
    }
}

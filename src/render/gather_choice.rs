//! The gather's slot in the frame (`plan::Pass::Gather`): the gather `render.gather` names (per
//! vertex, sparse, hierarchical, texture, or per pixel when the scene's needs say so), followed
//! by the between-points single scattering where an object takes it. Each of those is a pass of
//! its own module and GLSL; this one only chooses among them.

use super::beam_gather::BeamGatherPass;
use super::error::RenderError;
use super::gather::GatherPass;
use super::gather_pixel::GatherPixelPass;
use super::gather_sparse::GatherSparsePass;
use super::gather_texture::GatherTexturePass;
use super::gather_tree::GatherTreePass;
use super::graph::Use;
use super::transport::TransportPass;
use super::pass::{FrameInputs, GatherThen, PassContext, Rebuild, RegisteredPass, RenderPass};
use crate::scene::GatherMode;
use ash::vk;

/// The chosen gather, recorded as it records.
pub struct GatherChoice(Box<dyn RenderPass>);

impl RegisteredPass for GatherChoice {
    // The scene's buffers are bound; the pixel gather binds the camera images too.
    const REBUILT_ON: &'static [Rebuild] = &[Rebuild::SceneData, Rebuild::Resize];

    fn build(context: &PassContext) -> Result<Option<Self>, RenderError> {
        let (gpu, resources) = (context.gpu, &context.resources);
        let settings = &context.scene.scene.file.render;
        let gather: Box<dyn RenderPass> = match settings.gather {
            _ if context.needs.pixel_gather => return Ok(Some(GatherChoice(Box::new(GatherPixelPass::new(gpu, resources)?)))),
            GatherMode::Sparse => Box::new(GatherSparsePass::new(gpu, resources)?),
            GatherMode::Hierarchical => Box::new(GatherTreePass::new(gpu, resources, context.options.depth)?),
            GatherMode::Texture => Box::new(GatherTexturePass::new(gpu, resources, settings.texture_samples)?),
            _ => Box::new(GatherPass::new(gpu, resources)?),
        };
        // Channels of single scattering between points overwrite the dipole's after it.
        let gather: Box<dyn RenderPass> = match BeamGatherPass::new(gpu, resources)? {
            Some(beams) => Box::new(GatherThen { gather, then: beams }),
            None => gather,
        };
        // Then the transport kernels scale the per-vertex exitance of the objects that have
        // one (the texture gather's lives in its atlas: there the dipole alone).
        let per_vertex = settings.gather != GatherMode::Texture;
        Ok(Some(GatherChoice(match TransportPass::new(gpu, resources)?.filter(|_| per_vertex) {
            Some(transport) => Box::new(GatherThen { gather, then: transport }),
            None => gather,
        })))
    }
}

impl RenderPass for GatherChoice {
    fn uses(&self, frame: &FrameInputs) -> Vec<Use> {
        self.0.uses(frame)
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        self.0.record(cmd, frame);
    }
}

//! The frame's passes, registered once. Each line of `for_each_pass!` names a pass: the planner's
//! `plan::Pass` variant, its name in plans and timings, and the module and type that build and
//! record it (`pass::RegisteredPass`). The planner's enum (`plan::Pass`) and the renderer's table
//! of passes (`renderer::passes`) are both generated from this one list, so a new pass is one
//! GLSL file, one module and one line here. The order is the order of `Pass` (the planner still
//! decides which passes a frame runs, and in which order they are recorded).

/// Calls `$then!` with every registered pass, one `Variant = "name": module::Type,` each, with
/// its doc comment.
macro_rules! for_each_pass {
    ($then:ident) => {
        $then! {
            /// Shadow maps of the shadow-casting lights (`ShadowPass`, glsl/shadow.vert).
            Shadow = "shadow": shadow::ShadowPass,
            /// The environment light's irradiance cached per vertex (`VertexLightPass`).
            VertexLight = "vertex_light": vertex_light::VertexLightPass,
            /// Irradiance transmitted into every sample point (`SplatPass`).
            Splat = "splat": splat::SplatPass,
            /// Exitance summed from the samples' dipoles: per vertex, sparse or per pixel
            /// (`render.gather`; `GatherChoice`).
            Gather = "gather": gather_choice::GatherChoice,
            /// The camera's view rasterised into the HDR image or the host's target (`ShadePass`).
            Shade = "shade": shade::ShadePass,
            /// HDR to 8-bit sRGB for readback (`TonemapPass`); own target only.
            Tonemap = "tonemap": tonemap::TonemapPass,
            /// A test's pass: exitance doubled into the local-exitance buffer (`ProbePass`), which
            /// no frame's plan runs unless a test records it (`Renderer::record_plan`).
            #[cfg(test)]
            Probe = "probe": probe::ProbePass,
        }
    };
}

pub(crate) use for_each_pass;

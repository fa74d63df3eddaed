//! Pass planning: which GPU passes a frame needs, and why. A scene simulates only what it calls
//! for (no shadow maps without a shadow-casting light and caster, no splat or gather without a
//! translucent object), and a frame recomputes only what its change invalidates: light changes
//! rerun shadows, splat and gather; a camera move reruns only shading (vertex gather: exitance
//! lives on the surface and does not depend on the view).

pub use crate::scene::needs::SceneNeeds;
use std::fmt;

/// A GPU pass the planner can schedule; `Renderer::pass` maps each to its `RenderPass`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// Shadow maps of the shadow-casting lights (`ShadowPass`, glsl/shadow.vert).
    Shadow,
    /// The environment light's irradiance cached per vertex (`VertexLightPass`).
    VertexLight,
    /// Irradiance transmitted into every sample point (`SplatPass`).
    Splat,
    /// Exitance summed from the samples' dipoles: per vertex, sparse or per pixel
    /// (`render.gather`).
    Gather,
    /// The camera's view rasterised into the HDR image or the host's target (`ShadePass`).
    Shade,
    /// HDR to 8-bit sRGB for readback (`TonemapPass`); own target only.
    Tonemap,
}

impl Change {
    /// The change covering both `self` and `other` (what a frame must redo after both).
    pub fn and(self, other: Change) -> Change {
        use Change::*;
        match (self, other) {
            (Everything, _) | (_, Everything) => Everything,
            (Lights, _) | (_, Lights) => Lights,
            (Light(a), Light(b)) if a != b => Lights,
            (Light(a), _) | (_, Light(a)) => Light(a),
            (Camera, Camera) => Camera,
        }
    }
}

impl Pass {
    /// The pass's name in plans, timer marks and `FrameTimings`, e.g. "vertex_light".
    pub fn name(self) -> &'static str {
        match self {
            Pass::Shadow => "shadow",
            Pass::VertexLight => "vertex_light",
            Pass::Splat => "splat",
            Pass::Gather => "gather",
            Pass::Shade => "shade",
            Pass::Tonemap => "tonemap",
        }
    }
}

/// What changed since the last frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// Nothing computed yet.
    Everything,
    /// Every light moved or changed: all visibility and irradiance are stale.
    Lights,
    /// One light (index in the scene's lights) moved: only its shadow maps are stale, but the
    /// irradiance it adds to every sample is.
    Light(usize),
    /// Only the camera moved.
    Camera,
}

/// The passes one frame runs, in recording order, and the ones it skips, each with its reason;
/// `Display` prints one a line.
#[derive(Clone, Debug, Default)]
pub struct Plan {
    /// Passes to record, in order, each with why it runs.
    pub passes: Vec<(Pass, String)>,
    /// Passes left out, each with why: their last results are reused, or the scene does not need
    /// them.
    pub skipped: Vec<(Pass, String)>,
    /// When only one light's shadow maps are redrawn: that scene light; `None` redraws all.
    pub shadow_light: Option<usize>,
}

impl Plan {
    /// Whether `pass` is among the passes to record.
    pub fn runs(&self, pass: Pass) -> bool {
        self.passes.iter().any(|(p, _)| *p == pass)
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (p, why) in &self.passes {
            writeln!(f, "  run  {:<8} {why}", p.name())?;
        }
        for (p, why) in &self.skipped {
            writeln!(f, "  skip {:<8} {why}", p.name())?;
        }
        Ok(())
    }
}

/// The plan for a scene with `needs` after `change`: which passes run, in order, and why, and why
/// the others are skipped (the rules are in the module doc). The pixel gather runs after shading,
/// the other gathers before it.
pub fn plan(needs: &SceneNeeds, change: Change) -> Plan {
    let mut plan = Plan::default();
    let lights_stale = matches!(change, Change::Everything | Change::Lights | Change::Light(_));
    let mut add = |pass: Pass, run: bool, yes: &str, no: &str| {
        if run {
            plan.passes.push((pass, yes.to_string()));
        } else {
            plan.skipped.push((pass, no.to_string()));
        }
    };
    let has_shadows = needs.shadow_layers > 0;
    match change {
        Change::Light(i) if !needs.shadowed_lights.contains(&i) => add(
            Pass::Shadow,
            false,
            "",
            if has_shadows { "the moved light casts no shadow: shadow maps reused" } else { "no shadow-casting light" },
        ),
        Change::Light(_) => {
            add(Pass::Shadow, true, "one light moved: only its shadow maps are redrawn, the others are reused", "")
        }
        _ => add(
            Pass::Shadow,
            has_shadows && lights_stale,
            "lights changed: shadow maps are stale",
            if has_shadows {
                "lights and geometry unchanged: shadow maps reused"
            } else {
                "no light casts a shadow onto a caster"
            },
        ),
    }
    if let Change::Light(i) = change {
        plan.shadow_light = Some(i);
    }
    let environment_stale = match change {
        Change::Everything | Change::Lights => true,
        Change::Light(i) => needs.environment == Some(i),
        Change::Camera => false,
    };
    add(
        Pass::VertexLight,
        needs.environment.is_some() && environment_stale,
        "the environment changed: per-vertex sky irradiance is stale",
        if needs.environment.is_some() {
            "the environment is unchanged: per-vertex sky irradiance reused"
        } else {
            "no environment light"
        },
    );
    let translucent = needs.translucent_objects > 0;
    add(
        Pass::Splat,
        translucent && lights_stale,
        "lights changed: irradiance at the samples is stale",
        if translucent { "lights unchanged: sample irradiance reused" } else { "no translucent object" },
    );
    if needs.pixel_gather {
        add(Pass::Shade, true, "every frame draws the view (and, for the pixel gather, each pixel's surface)", "");
        add(
            Pass::Gather,
            translucent,
            "pixel gather: the receivers are the pixels in view, redone every frame",
            "no translucent object",
        );
    } else {
        add(
            Pass::Gather,
            translucent && lights_stale,
            "sample irradiance changed: exitance is stale",
            if translucent { "exitance is view-independent and unchanged: reused" } else { "no translucent object" },
        );
        add(Pass::Shade, true, "every frame draws the view", "");
    }
    add(
        Pass::Tonemap,
        !needs.host_target,
        "every frame's HDR image is tone-mapped",
        "the host tone-maps its own target",
    );
    plan
}

#[cfg(test)]
mod tests {
    use super::*;

    fn needs(shadow_layers: u32, translucent_objects: usize) -> SceneNeeds {
        SceneNeeds {
            shadow_layers,
            translucent_objects,
            shadowed_lights: if shadow_layers > 0 { vec![0] } else { vec![] },
            environment: (shadow_layers > 1).then_some(1),
            pixel_gather: false,
            host_target: false,
        }
    }

    #[test]
    fn a_camera_move_only_shades() {
        let p = plan(&needs(3, 1), Change::Camera);
        assert!(p.runs(Pass::Shade) && p.runs(Pass::Tonemap));
        assert!(!p.runs(Pass::Shadow) && !p.runs(Pass::Splat) && !p.runs(Pass::Gather));
        assert!(!p.runs(Pass::VertexLight));
    }

    #[test]
    fn scenes_without_translucency_or_shadows_skip_those_passes() {
        let p = plan(&needs(0, 0), Change::Everything);
        assert_eq!(p.passes.iter().map(|(p, _)| *p).collect::<Vec<_>>(), [Pass::Shade, Pass::Tonemap]);
        assert_eq!(p.skipped.len(), 4);
        let p = plan(&needs(2, 1), Change::Everything);
        assert_eq!(p.passes.len(), 6);
    }

    #[test]
    fn the_pixel_gather_follows_the_camera() {
        let mut n = needs(3, 1);
        n.pixel_gather = true;
        let p = plan(&n, Change::Camera);
        let order: Vec<Pass> = p.passes.iter().map(|(p, _)| *p).collect();
        assert_eq!(order, [Pass::Shade, Pass::Gather, Pass::Tonemap]);
    }

    #[test]
    fn one_moved_light_redraws_only_its_shadows() {
        let p = plan(&needs(3, 1), Change::Light(0));
        assert!(p.runs(Pass::Shadow) && p.runs(Pass::Splat) && p.runs(Pass::Gather));
        assert!(!p.runs(Pass::VertexLight), "the environment did not move");
        assert_eq!(p.shadow_light, Some(0));
        let p = plan(&needs(3, 1), Change::Light(5));
        assert!(!p.runs(Pass::Shadow) && p.runs(Pass::Splat));
    }
}

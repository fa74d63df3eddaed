//! The rules for each pass (shadows, the environment, splat and gather, shading and tone map)
//! and the order they are recorded in.

use super::frame::Frame;
use super::{Change, ObjectPlan, Pass, PassReason, SHADOW_ONE_TAP_PIXELS, SceneNeeds, ShadowFilter, SkipReason, View};
use glam::Vec3;

/// One pass's decision this frame.
enum Decision {
    Run(PassReason),
    Skip(SkipReason),
}

use Decision::{Run, Skip};

/// Passes to record, each with why, and passes skipped, each with why (`Plan::passes`, `skipped`).
type Sorted = (Vec<(Pass, PassReason)>, Vec<(Pass, SkipReason)>);

impl Frame<'_> {
    /// The passes to record, in order, and those skipped, each with its reason, given the
    /// objects' plans. The pixel gather runs after shading (it reads each pixel's surface), the
    /// other gathers before it.
    pub(super) fn passes(&self, objects: &[ObjectPlan]) -> Sorted {
        let (splat, gather) = self.sample_passes(objects);
        let shade = Run(if self.needs.pixel_gather { PassReason::DrawsViewAndSurfaces } else { PassReason::DrawsView });
        let tonemap =
            if self.needs.host_target { Skip(SkipReason::HostToneMaps) } else { Run(PassReason::ToneMapsEveryFrame) };
        let mut order =
            vec![(Pass::Shadow, self.shadows()), (Pass::VertexLight, self.environment()), (Pass::Splat, splat)];
        if self.needs.pixel_gather {
            order.extend([(Pass::Shade, shade), (Pass::Gather, gather)]);
        } else {
            order.extend([(Pass::Gather, gather), (Pass::Shade, shade)]);
        }
        order.push((Pass::Tonemap, tonemap));
        let (mut passes, mut skipped) = (Vec::new(), Vec::new());
        for (pass, decision) in order {
            match decision {
                Run(why) => passes.push((pass, why)),
                Skip(why) => skipped.push((pass, why)),
            }
        }
        (passes, skipped)
    }

    /// Shadow maps: redrawn when lights or geometry changed (only the moved light's, when one
    /// light moved).
    fn shadows(&self) -> Decision {
        let has_shadows = self.needs.shadow_layers > 0;
        match self.change {
            Change::Light(_) if !has_shadows => Skip(SkipReason::NoShadowCastingLight),
            _ if !has_shadows => Skip(SkipReason::NoShadowCaster),
            Change::Light(i) if !self.needs.shadowed_lights.contains(&i) => Skip(SkipReason::MovedLightCastsNoShadow),
            Change::Light(_) => Run(PassReason::OneLightMoved),
            Change::Geometry(_) => Run(PassReason::GeometryMoved),
            _ if self.lights_stale => Run(PassReason::LightsChanged),
            _ => Skip(SkipReason::ShadowsCurrent),
        }
    }

    /// The environment's per-vertex cache: recomputed when the environment or the geometry
    /// changed.
    fn environment(&self) -> Decision {
        match self.needs.environment {
            None => Skip(SkipReason::NoEnvironment),
            Some(_) if self.environment_stale => Run(PassReason::SkyLightStale),
            Some(_) => Skip(SkipReason::SkyLightCurrent),
        }
    }

    /// Splat and gather, over the objects whose plans call for them. The pixel gather also
    /// finishes every pixel's HDR alpha (shade_pixel.frag leaves a factor there), so it runs
    /// whenever the scene has a translucent object; its pixels of local or unseen objects cost a
    /// texel fetch each.
    fn sample_passes(&self, objects: &[ObjectPlan]) -> (Decision, Decision) {
        let list =
            |f: fn(&ObjectPlan) -> bool| -> Vec<usize> { objects.iter().filter(|o| f(o)).map(|o| o.object).collect() };
        let (splatted, gathered) = (list(|o| o.splat), list(|o| o.gather));
        let translucent = self.needs.translucent_objects > 0;
        let none = |current| if translucent { current } else { SkipReason::NoTranslucentObject };
        let splat = if splatted.is_empty() {
            Skip(none(SkipReason::SampleIrradianceCurrent))
        } else {
            Run(PassReason::SampleIrradianceStale { objects: splatted })
        };
        let gather = if self.needs.pixel_gather && translucent {
            Run(PassReason::PixelGather { objects: gathered })
        } else if !self.needs.pixel_gather && !gathered.is_empty() {
            Run(PassReason::ExitanceStale { objects: gathered })
        } else {
            Skip(none(SkipReason::ExitanceCurrent))
        };
        (splat, gather)
    }
}

/// Shading's shadow filter: one tap when a shadow-map texel at the casters' centre is at most
/// `SHADOW_ONE_TAP_PIXELS` pixels, else the four-tap tent; `None` without shadows.
pub(super) fn shadow_filter(needs: &SceneNeeds, view: &View) -> Option<ShadowFilter> {
    (needs.shadow_layers > 0).then(|| {
        let px = view.pixel_footprint(Vec3::from(needs.caster_center).distance(view.eye) as f64);
        let texel_pixels = needs.shadow_texel / px;
        ShadowFilter { one_tap: texel_pixels <= SHADOW_ONE_TAP_PIXELS, texel_pixels }
    })
}

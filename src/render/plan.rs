//! Pass planning: which GPU passes a frame needs, for which objects, and why. A scene
//! simulates only what it calls for, and a frame recomputes only what its change invalidates:
//!
//! - Physics, per translucent object and colour channel (`choose`): `local` computes the
//!   exitance at each receiver as `M = R_d,total E_t` (no splat, no gather), `gather` sums the
//!   dipoles of the samples. Local is what the dipole integral gives when the transmitted
//!   irradiance is uniform over the profile; to second order it is off by
//!   `R_d,total <r^2> laplacian(E_t) / 4`, with `<r^2>` the profile's mean squared radius
//!   (`Dipole::profile_radius`). So a channel goes local when the blur that radius gives is
//!   not there to see: when it is at most `LOCAL_PIXELS` pixel footprints on the object, or when
//!   the samples lie `LOCAL_SPACING` or more profile radii apart (then the sum sees little more
//!   than each sample's own disk: a local answer at the samples, interpolated to the receivers,
//!   which is worse than the local answer at the receiver itself). A profile wider than the
//!   object means light spreads through all of it; the dipole (a semi-infinite slab) is then a
//!   weak model, and the object is gathered over all its samples.
//! - View: a translucent object outside the view frustum gets no splat or gather (light does not
//!   pass between objects in this model); its exitance stays stale until it comes into view.
//! - Changes: lights rerun shadows (only the moved light's maps), the environment's per-vertex
//!   cache (only when the environment changed) and every object's splat and gather; a material
//!   reruns that object's splat and gather (its samples stay); geometry resamples that object
//!   and reruns everything lit; a camera move reruns shading (and the pixel gather), plus the
//!   splat and gather of objects that come into view stale or whose channels turn to gather.

use crate::scene::TransportMode;
use crate::scene::needs::ObjectFacts;
pub use crate::scene::needs::SceneNeeds;
use glam::{Mat4, Vec3, Vec4};
use std::fmt;

/// A channel goes local when its profile's RMS radius is at most this many pixel footprints on
/// the object: the blur transport adds is under a pixel. README ("Local or gathered") gives the
/// image error it was checked with.
pub const LOCAL_PIXELS: f64 = 1.0;

/// A channel goes local when its samples lie at least this many profile radii apart: the sum
/// then resolves too little of the profile (the seed, section 3, asks for samples closer than
/// the mean free path). Measured against the exact integral (docs/STUDY.md, defect 4: the 2 cm
/// ketchup sphere, Turk's samples, per-vertex error per channel), the local model beat the
/// gather at every spacing of 2.4 profile radii and more, and lost at every spacing of 1.7 and
/// less; 4, the first choice, kept gathering where the gather was 1.4x to 3x worse.
pub const LOCAL_SPACING: f64 = 2.0;
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
    /// The change covering both `self` and `other` (what a frame must redo after both). A
    /// material change folded into another names one object; the renderer keeps every changed
    /// object stale itself, so nothing is lost.
    pub fn and(self, other: Change) -> Change {
        use Change::*;
        match (self, other) {
            (Everything, _) | (_, Everything) => Everything,
            (Geometry(a), Geometry(b)) if a == b => Geometry(a),
            (Geometry(a), Camera | Material(_)) | (Camera | Material(_), Geometry(a)) => Geometry(a),
            (Geometry(_), _) | (_, Geometry(_)) => Everything,
            (Lights, _) | (_, Lights) => Lights,
            (Light(a), Light(b)) if a != b => Lights,
            (Light(a), _) | (_, Light(a)) => Light(a),
            (Material(a), _) | (_, Material(a)) => Material(a),
            (Camera, Camera) => Camera,
        }
    }

    /// Every kind of change a scene with `lights` lights and `objects` objects can have, for
    /// `translucent plan`: everything, all lights, each light, the camera, each object's material
    /// and geometry.
    pub fn all(lights: usize, objects: usize) -> Vec<Change> {
        let mut all = vec![Change::Everything, Change::Lights];
        all.extend((0..lights).map(Change::Light));
        all.push(Change::Camera);
        all.extend((0..objects).map(Change::Material));
        all.extend((0..objects).map(Change::Geometry));
        all
    }
}

impl fmt::Display for Change {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Change::Everything => write!(f, "everything"),
            Change::Lights => write!(f, "lights"),
            Change::Light(i) => write!(f, "light {i}"),
            Change::Camera => write!(f, "camera"),
            Change::Material(i) => write!(f, "material of object {i}"),
            Change::Geometry(i) => write!(f, "geometry of object {i}"),
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
    /// One object's material coefficients changed: its samples stay, its splat and gather rerun.
    Material(usize),
    /// One object's geometry or transform changed: it is resampled, and shadows and every
    /// object's irradiance are stale.
    Geometry(usize),
}

/// How one colour channel of a translucent object gets its exitance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Transport {
    /// `M = R_d,total E_t` at each receiver: no sampling, splat or gather for the channel.
    Local,
    /// The dipole sum over the object's samples (`render.gather`).
    Gather,
}

/// The planner's choice for one channel, with the numbers that decided it (scene units).
#[derive(Clone, Debug, serde::Serialize)]
pub struct ChannelPlan {
    /// Local or gathered.
    pub transport: Transport,
    /// Why, in words, with the figures.
    pub why: String,
}

/// What one object gets this frame, and why.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ObjectPlan {
    /// Index in the scene.
    pub object: usize,
    /// Mesh path or shape.
    pub name: String,
    /// Whether its bounding sphere meets the view frustum.
    pub in_view: bool,
    /// Scene units one pixel covers at the object's nearest point (`None` when out of view).
    pub pixel_footprint: Option<f64>,
    /// Per channel (R, G, B) of a translucent object; empty for an opaque one.
    pub channels: Vec<ChannelPlan>,
    /// Its samples' irradiance is computed this frame.
    pub splat: bool,
    /// Its exitance is gathered this frame.
    pub gather: bool,
    /// Why it is (or is not) splatted and gathered.
    pub why: String,
    /// Whether its gathered exitance still needs recomputing after this frame (lights or its
    /// material changed and it was not gathered).
    pub stale_after: bool,
    /// The level of detail it is drawn, shadowed and gathered at (0: the whole mesh;
    /// `choose_level`).
    pub level: usize,
    /// Why that level, with the figures.
    pub level_why: String,
}

impl ObjectPlan {
    /// Bit c set when channel c is local (`ObjectRecord`'s `eta_norm_kind.w`).
    pub fn local_mask(&self) -> u32 {
        self.channels.iter().enumerate().filter(|(_, c)| c.transport == Transport::Local).map(|(i, _)| 1 << i).sum()
    }
}

/// The passes one frame runs, in recording order, the ones it skips, each with its reason, and
/// what each object gets; `Display` prints one a line.
#[derive(Clone, Debug, Default)]
pub struct Plan {
    /// What changed (`None` for a plan made by hand).
    pub change: Option<Change>,
    /// Passes to record, in order, each with why it runs.
    pub passes: Vec<(Pass, String)>,
    /// Passes left out, each with why: their last results are reused, or the scene does not need
    /// them.
    pub skipped: Vec<(Pass, String)>,
    /// When only one light's shadow maps are redrawn: that scene light; `None` redraws all.
    pub shadow_light: Option<usize>,
    /// Per object, in scene order (empty in a plan made by hand: every object runs).
    pub objects: Vec<ObjectPlan>,
    /// Shading looks each key light's shadow up with one bilinear tap instead of four (a 3x3
    /// texel tent): a texel is small on screen, so the tent's softening is below a pixel or
    /// two (`SHADOW_ONE_TAP_PIXELS`). False in a plan made by hand.
    pub one_tap_shadows: bool,
    /// Why that filter, with the figures.
    pub shadow_filter_why: String,
    /// Terms of the shading pass left out (`shade::TERM_*` bits), to measure what each costs
    /// (the benchmark's `terms` section); 0, every term, in any plan the planner makes.
    pub skip_terms: u32,
}

impl Plan {
    /// Whether `pass` is among the passes to record.
    pub fn runs(&self, pass: Pass) -> bool {
        self.passes.iter().any(|(p, _)| *p == pass)
    }

    /// Whether object `object`'s samples are splatted (when the splat runs).
    pub fn splats(&self, object: usize) -> bool {
        self.objects.get(object).is_none_or(|o| o.splat)
    }

    /// Whether object `object` is gathered (when the gather runs).
    pub fn gathers(&self, object: usize) -> bool {
        self.objects.get(object).is_none_or(|o| o.gather)
    }

    /// The level of detail object `object` is drawn and gathered at (0, the whole mesh, in a
    /// plan made by hand).
    pub fn level(&self, object: usize) -> usize {
        self.objects.get(object).map_or(0, |o| o.level)
    }

    /// The plan as JSON, the shape `translucent plan --json` prints (docs/PLAN.md):
    /// `{change, passes: [{pass, why}], skipped: [{pass, why}], shadow_light, objects: [...]}`.
    pub fn to_json(&self) -> serde_json::Value {
        let list = |v: &[(Pass, String)]| {
            v.iter().map(|(p, why)| serde_json::json!({"pass": p.name(), "why": why})).collect::<Vec<_>>()
        };
        serde_json::json!({
            "change": self.change.map(|c| c.to_string()),
            "passes": list(&self.passes),
            "skipped": list(&self.skipped),
            "shadow_light": self.shadow_light,
            "one_tap_shadows": self.one_tap_shadows,
            "shadow_filter_why": self.shadow_filter_why,
            "objects": self.objects,
        })
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (p, why) in &self.passes {
            writeln!(f, "  run  {:<12} {why}", p.name())?;
        }
        for (p, why) in &self.skipped {
            writeln!(f, "  skip {:<12} {why}", p.name())?;
        }
        if !self.shadow_filter_why.is_empty() {
            writeln!(f, "  shadow filter: {}", self.shadow_filter_why)?;
        }
        for o in self.objects.iter().filter(|o| !o.channels.is_empty() || o.level > 0) {
            writeln!(f, "  object {} ({}): {}", o.object, o.name, o.why)?;
            writeln!(f, "    level {}: {}", o.level, o.level_why)?;
            for (c, ch) in ["R", "G", "B"].iter().zip(&o.channels) {
                let t = match ch.transport {
                    Transport::Local => "local ",
                    Transport::Gather => "gather",
                };
                writeln!(f, "    {c} {t} {}", ch.why)?;
            }
        }
        Ok(())
    }
}

/// Where the camera looks from, as the planner needs it.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// World -> clip (Vulkan clip space: depth 0..1).
    pub view_proj: Mat4,
    /// View -> clip alone, for the pixel footprint.
    pub projection: Mat4,
    /// Camera position.
    pub eye: Vec3,
    /// Image height in pixels.
    pub height: u32,
}

impl View {
    /// The view from `camera` onto an image `height` pixels high.
    pub fn of_camera(camera: &crate::render::renderer::CameraView, height: u32) -> View {
        View { view_proj: camera.projection * camera.view, projection: camera.projection, eye: camera.eye, height }
    }

    /// Whether a sphere meets the frustum (each of the six clip planes, Gribb and Hartmann's
    /// extraction from the matrix's rows, Vulkan depth 0..1).
    pub fn sees(&self, center: Vec3, radius: f32) -> bool {
        let m = self.view_proj;
        let (r0, r1, r2, r3) = (m.row(0), m.row(1), m.row(2), m.row(3));
        let planes: [Vec4; 6] = [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2];
        planes.iter().all(|p| {
            let n = p.truncate();
            let len = n.length();
            len == 0.0 || p.dot(center.extend(1.0)) >= -radius * len
        })
    }

    /// Scene units a pixel covers at distance `distance` from the eye: `2 d / (P_11 H)` under a
    /// perspective projection, `2 / (P_11 H)` under an orthographic one.
    pub fn pixel_footprint(&self, distance: f64) -> f64 {
        let p11 = (self.projection.y_axis.y as f64).abs().max(1e-12);
        let per_unit = 2.0 / (p11 * self.height.max(1) as f64);
        if self.projection.w_axis.w == 1.0 { per_unit } else { per_unit * distance }
    }
}

/// Largest shadow-map texel, in pixels at the casters' centre, that shading looks up with one
/// bilinear tap rather than the four-tap tent: the tent widens a shadow edge by about two
/// texels, which is then under two pixels. (On llvmpipe one compare tap costs nearly what four
/// do, README "Performance"; on a GPU the saving is the taps.)
pub const SHADOW_ONE_TAP_PIXELS: f64 = 1.0;

/// Longest mean edge, in pixels at the object's centre, that a level of detail may have. The
/// exitance a level carries varies over the diffusion profile's width (20 to 36 px on the
/// default scene), so edges well past a few pixels still carry it; on the default scene the
/// error limit binds first, and levels with 11 and 16 px edges stay under FLIP 0.02 against
/// the whole mesh (`cargo bench --bench render -- levels`, README "Performance").
pub const LOD_EDGE_PIXELS: f64 = 12.0;
/// Largest distance from the full mesh, in pixels at the object's centre, that a level
/// may have: the silhouette moves by less than half a pixel.
pub const LOD_ERROR_PIXELS: f64 = 0.5;

/// The coarsest of `facts.levels` whose mean edge and distance from the full mesh stay within
/// `LOD_EDGE_PIXELS` and `LOD_ERROR_PIXELS` pixels of footprint `footprint` (scene units per
/// pixel at the object's centre); out of view (`None`), the coarsest level (its draw is clipped
/// away, and shadow maps choose their own level, `GpuScene::casters`). Returns the level and why.
pub fn choose_level(facts: &ObjectFacts, footprint: Option<f64>) -> (usize, String) {
    let last = facts.levels.len().saturating_sub(1);
    if last == 0 {
        return (0, "drawn whole (one level: render.level_of_detail off, or per-vertex sky light)".into());
    }
    let Some(px) = footprint else {
        return (last, "out of view: its coarsest level (clipped away; shadow maps choose their own)".into());
    };
    // A level simplified around the vertices where its values vary keeps them wherever they
    // vary: only its distance from the whole mesh limits it.
    let fits = |l: &crate::scene::needs::LevelFacts| {
        (l.locked || l.mean_edge <= LOD_EDGE_PIXELS * px) && l.error <= LOD_ERROR_PIXELS * px
    };
    let level = (0..=last).rev().find(|&i| fits(&facts.levels[i])).unwrap_or(0);
    let l = &facts.levels[level];
    let why = format!(
        "{} of {} triangles, {} vertices: edges {:.2} px, error {:.2} px at {:.3e} units/px (limits {LOD_EDGE_PIXELS}, \
         {LOD_ERROR_PIXELS})",
        l.triangles,
        facts.levels[0].triangles,
        l.vertices,
        l.mean_edge / px,
        l.error / px,
        px
    );
    (level, why)
}

/// The choice for each channel of a translucent object seen with pixel footprint `footprint`
/// (`None`: out of view, judged by its samples and mesh alone), under `mode`.
pub fn choose(facts: &ObjectFacts, footprint: Option<f64>, mode: TransportMode) -> Vec<ChannelPlan> {
    let Some(channels) = &facts.channels else { return Vec::new() };
    let (s, v) = (facts.sample_spacing, facts.vertex_spacing);
    let p = footprint.unwrap_or(0.0);
    channels
        .iter()
        .map(|c| {
            let r = c.profile_radius;
            let numbers = format!(
                "(profile radius {r:.3e}, diffusion length {:.3e}, z_v {:.3e}; sample spacing {s:.3e}, vertex \
                 spacing {v:.3e}, pixel {p:.3e})",
                c.diffusion_length, c.z_v
            );
            let (transport, why) = match mode {
                TransportMode::Gather => (Transport::Gather, format!("render.transport = \"gather\" {numbers}")),
                TransportMode::Local => (Transport::Local, format!("render.transport = \"local\" {numbers}")),
                TransportMode::Auto if r > facts.radius as f64 => (
                    Transport::Gather,
                    format!(
                        "the profile is wider than the object (radius {:.3e}): light spreads through all of it, where \
                         the dipole's semi-infinite slab is a weak model; gathered over every sample {numbers}",
                        facts.radius
                    ),
                ),
                TransportMode::Auto if r <= LOCAL_PIXELS * p => (
                    Transport::Local,
                    format!("the profile is narrower than a pixel: its blur does not show, local {numbers}"),
                ),
                TransportMode::Auto if LOCAL_SPACING * r <= s => (
                    Transport::Local,
                    format!(
                        "the samples lie {:.1} profile radii apart (local from {LOCAL_SPACING}): the sum cannot \
                         resolve the profile, local {numbers}",
                        s / r
                    ),
                ),
                TransportMode::Auto => (
                    Transport::Gather,
                    format!(
                        "the profile spans {:.1} pixels and the samples resolve it: gathered {numbers}",
                        r / p.max(1e-30)
                    ),
                ),
            };
            ChannelPlan { transport, why }
        })
        .collect()
}

/// The plan for a scene with `needs`, seen from `view`, after `change`; `stale[i]` says object
/// i's gathered exitance was already out of date (lights or material changed while it was out
/// of view or local). The rules are in the module doc. The pixel gather runs after shading, the
/// other gathers before it.
///
/// `stale[i]`: object i's gathered exitance is out of date. `gathered[i]`: the finest level of
/// detail whose vertices hold object i's current exitance (`usize::MAX`: none); a finer level
/// coming into use is gathered again, from the samples' irradiance as it is.
pub fn plan(needs: &SceneNeeds, view: &View, stale: &[bool], gathered: &[usize], change: Change) -> Plan {
    let mut plan = Plan { change: Some(change), ..Plan::default() };
    let lights_stale = matches!(change, Change::Everything | Change::Lights | Change::Light(_) | Change::Geometry(_));
    let has_shadows = needs.shadow_layers > 0;
    let mut passes = Vec::new();
    let mut skipped = Vec::new();
    let mut add = |pass: Pass, run: bool, yes: String, no: String| {
        if run {
            passes.push((pass, yes));
        } else {
            skipped.push((pass, no));
        }
    };
    match change {
        Change::Light(i) if !needs.shadowed_lights.contains(&i) => add(
            Pass::Shadow,
            false,
            String::new(),
            if has_shadows { "the moved light casts no shadow: shadow maps reused" } else { "no shadow-casting light" }
                .into(),
        ),
        Change::Light(_) => add(
            Pass::Shadow,
            true,
            "one light moved: only its shadow maps are redrawn, the others are reused".into(),
            String::new(),
        ),
        _ => add(
            Pass::Shadow,
            has_shadows && lights_stale,
            if matches!(change, Change::Geometry(_)) {
                "geometry moved: every shadow map is stale".into()
            } else {
                "lights changed: shadow maps are stale".into()
            },
            if has_shadows {
                "lights and geometry unchanged: shadow maps reused".into()
            } else {
                "no light casts a shadow onto a caster".into()
            },
        ),
    }
    if let Change::Light(i) = change {
        plan.shadow_light = Some(i);
    }
    let environment_stale = match change {
        Change::Everything | Change::Lights | Change::Geometry(_) => true,
        Change::Light(i) => needs.environment == Some(i),
        Change::Camera | Change::Material(_) => false,
    };
    add(
        Pass::VertexLight,
        needs.environment.is_some() && environment_stale,
        "the environment or the geometry changed: per-vertex sky irradiance is stale".into(),
        if needs.environment.is_some() {
            "the environment and geometry are unchanged: per-vertex sky irradiance reused".into()
        } else {
            "no environment light".into()
        },
    );

    let mode = needs.transport;
    for (i, facts) in needs.objects.iter().enumerate() {
        let center = Vec3::from(facts.center);
        let in_view = view.sees(center, facts.radius);
        let nearest = (center.distance(view.eye) - facts.radius).max(0.0) as f64;
        let footprint = in_view.then(|| view.pixel_footprint(nearest));
        let channels = choose(facts, footprint, mode);
        // Levels are judged at the centre's distance: the bounding sphere's nearest point lies
        // well in front of most of the surface, and would keep far more triangles than pixels.
        let centre_footprint = in_view.then(|| view.pixel_footprint(center.distance(view.eye) as f64));
        let (mut level, mut level_why) = choose_level(facts, centre_footprint);
        if needs.environment.is_some() && environment_stale && facts.levels.iter().any(|l| l.locked) {
            level = 0;
            level_why = "whole: this frame recomputes the sky light its levels were baked from".into();
        }
        let finer = gathered.get(i).is_some_and(|&g| level < g);
        let stale_now = stale.get(i).copied().unwrap_or(true) || lights_stale || change == Change::Material(i);
        let gathered = channels.iter().any(|c| c.transport == Transport::Gather);
        let (splat, gather, why) = if channels.is_empty() {
            (false, false, "opaque".to_string())
        } else if !gathered {
            (false, false, "every channel local: no splat or gather".to_string())
        } else if !in_view {
            (
                false,
                false,
                "outside the view frustum: no splat or gather (light does not pass between objects); redone when \
                 it comes into view"
                    .to_string(),
            )
        } else if stale_now {
            let why = match change {
                Change::Material(m) if m == i && !lights_stale => {
                    "its material changed: same samples, new splat and gather"
                }
                Change::Geometry(m) if m == i => "its geometry changed: resampled, splat and gather",
                _ if lights_stale => "lights changed: splat and gather",
                _ => "in view again after lights or its material changed: splat and gather",
            };
            (true, true, why.to_string())
        } else if needs.pixel_gather {
            (false, true, "pixel gather: redone for the pixels in view every frame, sample irradiance reused".into())
        } else if finer {
            (
                false,
                true,
                format!(
                    "level {level} is finer than the last gathered: its vertices gathered, sample irradiance reused"
                ),
            )
        } else {
            (false, false, "lights and material unchanged: exitance is view-independent, reused".into())
        };
        let stale_after = !channels.is_empty() && stale_now && !gather;
        plan.objects.push(ObjectPlan {
            object: i,
            name: facts.name.clone(),
            in_view,
            pixel_footprint: footprint,
            channels,
            splat,
            gather,
            why,
            stale_after,
            level,
            level_why,
        });
    }
    let list = |f: &dyn Fn(&ObjectPlan) -> bool| -> Vec<usize> {
        plan.objects.iter().filter(|o| f(o)).map(|o| o.object).collect()
    };
    let (splatted, gathered) = (list(&|o| o.splat), list(&|o| o.gather));
    let translucent = needs.translucent_objects > 0;
    let none = |what: &str| {
        if translucent {
            format!("no translucent object needs {what} this frame (see the objects)")
        } else {
            "no translucent object".to_string()
        }
    };
    add(
        Pass::Splat,
        !splatted.is_empty(),
        format!("irradiance at the samples is stale for objects {splatted:?}"),
        none("its sample irradiance recomputed"),
    );
    // The pixel gather also finishes every pixel's HDR alpha (shade_pixel.frag leaves a factor
    // there), so it runs whenever the scene has a translucent object; its pixels of local or
    // unseen objects cost a texel fetch each.
    let gather_pass = (
        Pass::Gather,
        if needs.pixel_gather { translucent } else { !gathered.is_empty() },
        if needs.pixel_gather {
            format!("pixel gather: the receivers are the pixels in view of objects {gathered:?}")
        } else {
            format!("exitance is stale for objects {gathered:?}")
        },
        none("a gather"),
    );
    if needs.pixel_gather {
        add(
            Pass::Shade,
            true,
            "every frame draws the view (and, for the pixel gather, each pixel's surface)".into(),
            String::new(),
        );
        add(gather_pass.0, gather_pass.1, gather_pass.2, gather_pass.3);
    } else {
        add(gather_pass.0, gather_pass.1, gather_pass.2, gather_pass.3);
        add(Pass::Shade, true, "every frame draws the view".into(), String::new());
    }
    add(
        Pass::Tonemap,
        !needs.host_target,
        "every frame's HDR image is tone-mapped".into(),
        "the host tone-maps its own target".into(),
    );
    plan.passes = passes;
    plan.skipped = skipped;
    if has_shadows {
        let px = view.pixel_footprint(Vec3::from(needs.caster_center).distance(view.eye) as f64);
        let texel = needs.shadow_texel / px;
        plan.one_tap_shadows = texel <= SHADOW_ONE_TAP_PIXELS;
        plan.shadow_filter_why = format!(
            "{}: a shadow-map texel spans {texel:.2} px at the casters' centre (one tap up to {SHADOW_ONE_TAP_PIXELS})",
            if plan.one_tap_shadows { "one bilinear tap" } else { "four-tap tent" }
        );
    }
    plan
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::needs::{ChannelFacts, LevelFacts};

    fn object(radius: f32, spacing: f64, profile: f64) -> ObjectFacts {
        let channel = ChannelFacts { diffusion_length: profile, z_v: profile, profile_radius: profile, r_d_total: 0.5 };
        ObjectFacts {
            name: "sphere".into(),
            center: [0.0, 0.0, 0.0],
            radius,
            sample_spacing: spacing,
            vertex_spacing: spacing / 4.0,
            channels: Some([channel; 3]),
            levels: vec![LevelFacts {
                triangles: 1000,
                vertices: 500,
                mean_edge: spacing / 4.0,
                error: 0.0,
                locked: false,
            }],
        }
    }

    /// Three levels: 0.5, 5 and 20 pixels per edge at the origin in `view()` (0.1 units a
    /// pixel), 0, 0.2 and 0.1 pixels from the whole mesh.
    fn levels() -> Vec<LevelFacts> {
        [(1000, 0.05, 0.0), (250, 0.5, 0.02), (60, 2.0, 0.01)]
            .map(|(triangles, mean_edge, error)| LevelFacts {
                triangles,
                vertices: triangles / 2,
                mean_edge,
                error,
                locked: false,
            })
            .to_vec()
    }

    fn needs(shadow_layers: u32, translucent_objects: usize) -> SceneNeeds {
        SceneNeeds {
            shadow_layers,
            translucent_objects,
            shadowed_lights: if shadow_layers > 0 { vec![0] } else { vec![] },
            environment: (shadow_layers > 1).then_some(1),
            pixel_gather: false,
            host_target: false,
            transport: TransportMode::Auto,
            objects: (0..translucent_objects).map(|_| object(1.0, 0.1, 0.3)).collect(),
            shadow_texel: 0.01,
            caster_center: [0.0; 3],
        }
    }

    /// Looking down -z at the origin from z = 5, 90 degrees vertically, 100 pixels high.
    fn view() -> View {
        let projection = glam::camera::rh::proj::vulkan::perspective(std::f32::consts::FRAC_PI_2, 1.0, 0.1, 100.0);
        let view = glam::camera::rh::view::look_at_mat4(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y);
        View { view_proj: projection * view, projection, eye: Vec3::new(0.0, 0.0, 5.0), height: 100 }
    }

    fn run(needs: &SceneNeeds, change: Change) -> Plan {
        plan(needs, &view(), &vec![false; needs.objects.len()], &vec![0; needs.objects.len()], change)
    }

    #[test]
    fn the_coarsest_level_within_the_edge_and_error_limits_is_drawn() {
        let mut n = needs(1, 1);
        n.objects[0].levels = levels();
        let p = run(&n, Change::Camera);
        // Level 2's 20-pixel edges are past LOD_EDGE_PIXELS; level 1's 5 are within.
        assert_eq!(p.objects[0].level, 1, "{p}");
        assert!(p.objects[0].level_why.contains("250 of 1000 triangles"), "{p}");
        // Half a pixel from the whole mesh is the other limit: level 1 at 0.6 pixels is out.
        n.objects[0].levels[1].error = 0.06;
        assert_eq!(run(&n, Change::Camera).objects[0].level, 0);
    }

    #[test]
    fn a_finer_level_coming_into_use_is_gathered_again_without_a_splat() {
        let mut n = needs(1, 1);
        n.objects[0].levels = levels();
        // The last gather ran at level 2; this frame draws level 1, whose extra vertices lack it.
        let p = plan(&n, &view(), &[false], &[2], Change::Camera);
        assert!(p.runs(Pass::Gather) && p.objects[0].gather, "{p}");
        assert!(!p.runs(Pass::Splat), "the samples' irradiance is current: {p}");
        // At the level last gathered, or a coarser one, nothing is redone.
        let p = plan(&n, &view(), &[false], &[1], Change::Camera);
        assert!(!p.runs(Pass::Gather), "{p}");
    }

    #[test]
    fn levels_baked_from_sky_light_are_not_drawn_on_a_frame_that_recomputes_it() {
        // Light 1 is the environment (`needs` with 3 shadow layers).
        let mut n = needs(3, 1);
        n.objects[0].levels = levels();
        n.objects[0].levels.iter_mut().skip(1).for_each(|l| l.locked = true);
        // Locked levels are judged by their error alone: level 2's long edges do not count.
        assert_eq!(run(&n, Change::Camera).objects[0].level, 2);
        let p = run(&n, Change::Light(1));
        assert!(p.runs(Pass::VertexLight));
        assert_eq!(p.objects[0].level, 0, "{p}");
        assert!(p.objects[0].level_why.contains("recomputes the sky light"), "{p}");
        // The key light moving leaves the sky light, and the baked levels, as they are.
        assert_eq!(run(&n, Change::Light(0)).objects[0].level, 2);
    }

    #[test]
    fn out_of_view_an_object_takes_its_coarsest_level() {
        let mut n = needs(1, 1);
        n.objects[0].levels = levels();
        n.objects[0].center = [0.0, 0.0, 50.0];
        let p = run(&n, Change::Camera);
        assert!(!p.objects[0].in_view);
        assert_eq!(p.objects[0].level, 2, "{p}");
    }

    #[test]
    fn shadow_texels_smaller_than_a_pixel_are_looked_up_with_one_tap() {
        // 0.01 units a texel against 0.1 a pixel at the casters' centre.
        let mut n = needs(1, 1);
        assert!(run(&n, Change::Camera).one_tap_shadows);
        n.shadow_texel = 0.5;
        let p = run(&n, Change::Camera);
        assert!(!p.one_tap_shadows && p.shadow_filter_why.contains("four-tap"), "{p}");
    }

    #[test]
    fn a_camera_move_only_shades() {
        let p = run(&needs(3, 1), Change::Camera);
        assert!(p.runs(Pass::Shade) && p.runs(Pass::Tonemap));
        assert!(!p.runs(Pass::Shadow) && !p.runs(Pass::Splat) && !p.runs(Pass::Gather));
        assert!(!p.runs(Pass::VertexLight));
    }

    #[test]
    fn scenes_without_translucency_or_shadows_skip_those_passes() {
        let p = run(&needs(0, 0), Change::Everything);
        assert_eq!(p.passes.iter().map(|(p, _)| *p).collect::<Vec<_>>(), [Pass::Shade, Pass::Tonemap]);
        assert_eq!(p.skipped.len(), 4);
        let p = run(&needs(2, 1), Change::Everything);
        assert_eq!(p.passes.len(), 6);
    }

    #[test]
    fn the_pixel_gather_follows_the_camera() {
        let mut n = needs(3, 1);
        n.pixel_gather = true;
        let p = run(&n, Change::Camera);
        let order: Vec<Pass> = p.passes.iter().map(|(p, _)| *p).collect();
        assert_eq!(order, [Pass::Shade, Pass::Gather, Pass::Tonemap]);
        // Every channel local: the pixel gather still runs, to finish the HDR alpha.
        n.objects[0] = object(1.0, 0.1, 0.01);
        let p = run(&n, Change::Camera);
        assert!(p.runs(Pass::Gather) && !p.objects[0].gather && !p.runs(Pass::Splat), "{p}");
    }

    #[test]
    fn one_moved_light_redraws_only_its_shadows() {
        let p = run(&needs(3, 1), Change::Light(0));
        assert!(p.runs(Pass::Shadow) && p.runs(Pass::Splat) && p.runs(Pass::Gather));
        assert!(!p.runs(Pass::VertexLight), "the environment did not move");
        assert_eq!(p.shadow_light, Some(0));
        let p = run(&needs(3, 1), Change::Light(5));
        assert!(!p.runs(Pass::Shadow) && p.runs(Pass::Splat));
    }

    #[test]
    fn a_profile_narrower_than_the_finest_detail_goes_local_and_skips_splat_and_gather() {
        let mut n = needs(1, 1);
        n.objects[0] = object(1.0, 0.1, 0.01);
        let p = run(&n, Change::Everything);
        assert_eq!(p.objects[0].local_mask(), 0b111);
        assert!(!p.runs(Pass::Splat) && !p.runs(Pass::Gather), "{p}");
        // The same object whose profile is wider than the samples' spacing is gathered.
        n.objects[0] = object(1.0, 0.1, 0.3);
        assert_eq!(run(&n, Change::Everything).objects[0].local_mask(), 0);
        // Forced either way by render.transport.
        n.transport = TransportMode::Local;
        assert_eq!(run(&n, Change::Everything).objects[0].local_mask(), 0b111);
        n.transport = TransportMode::Gather;
        n.objects[0] = object(1.0, 0.1, 0.01);
        assert_eq!(run(&n, Change::Everything).objects[0].local_mask(), 0);
    }

    #[test]
    fn a_profile_wider_than_the_object_is_gathered_and_said_so() {
        let mut n = needs(1, 1);
        n.objects[0] = object(1.0, 5.0, 2.0);
        let p = run(&n, Change::Everything);
        assert_eq!(p.objects[0].local_mask(), 0);
        assert!(p.objects[0].channels[0].why.contains("wider than the object"), "{p}");
    }

    #[test]
    fn an_object_out_of_view_waits_stale_until_it_is_seen() {
        let mut n = needs(1, 1);
        n.objects[0].center = [0.0, 0.0, 10.0]; // behind the eye
        let p = run(&n, Change::Light(0));
        assert!(!p.objects[0].in_view && !p.runs(Pass::Splat) && !p.runs(Pass::Gather));
        assert!(p.objects[0].stale_after);
        // Back in view with nothing else changed: it is gathered then.
        n.objects[0].center = [0.0, 0.0, 0.0];
        let p = plan(&n, &view(), &[true], &[usize::MAX], Change::Camera);
        assert!(p.objects[0].in_view && p.runs(Pass::Splat) && p.runs(Pass::Gather));
        assert!(!p.objects[0].stale_after);
    }

    #[test]
    fn a_material_change_reruns_only_that_objects_splat_and_gather() {
        let mut n = needs(1, 2);
        n.objects[1].center = [0.5, 0.0, 0.0];
        let p = run(&n, Change::Material(1));
        assert!(!p.runs(Pass::Shadow) && p.runs(Pass::Splat) && p.runs(Pass::Gather));
        assert!(!p.objects[0].splat && p.objects[1].splat && p.objects[1].gather);
        let p = run(&n, Change::Geometry(1));
        assert!(p.runs(Pass::Shadow) && p.objects[0].gather && p.objects[1].gather);
    }

    #[test]
    fn the_view_sees_spheres_in_its_frustum_and_measures_pixels() {
        let v = view();
        assert!(v.sees(Vec3::ZERO, 0.1) && !v.sees(Vec3::new(0.0, 0.0, 6.0), 0.5));
        assert!(!v.sees(Vec3::new(20.0, 0.0, 0.0), 1.0) && v.sees(Vec3::new(5.0, 0.0, 0.0), 1.0));
        // 90 degrees over 100 pixels: 2 d tan(45) / 100 per pixel.
        assert!((v.pixel_footprint(5.0) - 0.1).abs() < 1e-6);
    }

    #[test]
    fn changes_fold_into_what_covers_both() {
        use Change::*;
        assert_eq!(Camera.and(Material(2)), Material(2));
        assert_eq!(Light(0).and(Material(2)), Light(0));
        assert_eq!(Geometry(1).and(Camera), Geometry(1));
        assert_eq!(Geometry(1).and(Light(0)), Everything);
        assert_eq!(Light(0).and(Light(1)), Lights);
    }
}

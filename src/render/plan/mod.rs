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
//!
//! The parts: `Planner` (planner.rs) holds what earlier frames left (the pending change, stale
//! objects, gathered levels, whether baked levels are current) and assembles a `Plan` from the
//! rules for each object (objects.rs) and each pass (passes.rs); every decision carries a reason
//! (reason.rs), text only when printed.

mod frame;
mod objects;
mod passes;
mod planner;
mod reason;
pub mod receivers;
#[cfg(test)]
mod tests;

pub use crate::scene::needs::SceneNeeds;
use glam::{Mat4, Vec3, Vec4};
pub use objects::{choose, choose_level};
pub use planner::{BakedLevels, Planner, needs};
pub use receivers::{EveryReason, ReceiverScope, SWEEP_FRAMES, Sweep};
pub use reason::{ChannelFigures, ChannelReason, LevelReason, ObjectReason, PassReason, ShadowFilter, SkipReason};
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
/// Declares `Pass` from the registry's list (`registry::for_each_pass!`).
macro_rules! declare_pass {
    ($( $(#[doc = $doc:literal])* $(#[cfg($cfg:meta)])? $variant:ident = $name:literal : $module:ident :: $ty:ident, )*) => {
        /// A GPU pass the planner can schedule: one per line of `registry::for_each_pass!`,
        /// which also gives the renderer the `RenderPass` that records it.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum Pass {
            $( $(#[doc = $doc])* $(#[cfg($cfg)])? $variant, )*
        }

        impl Pass {
            /// Every registered pass, in registration order.
            pub const ALL: &[Pass] = &[ $( $(#[cfg($cfg)])? Pass::$variant, )* ];

            /// The pass's name in plans, timer marks and `FrameTimings`, e.g. "vertex_light".
            pub fn name(self) -> &'static str {
                match self {
                    $( $(#[cfg($cfg)])? Pass::$variant => $name, )*
                }
            }
        }
    };
}

super::registry::for_each_pass!(declare_pass);

impl Change {
    /// The change covering both `self` and `other` (what a frame must redo after both). A
    /// material change folded into another names one object; `Planner::mark` keeps every changed
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

/// Which lights an object's splat evaluates this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SplatLights {
    /// Every light, the environment's directions included; their part is kept for later frames.
    #[default]
    All,
    /// The key lights alone, added to the environment's part an earlier splat kept: only key
    /// lights changed since (`GpuScene::splat_environment`).
    KeyLights,
}

/// The planner's choice for one channel, with the numbers that decided it (scene units).
#[derive(Clone, Debug, serde::Serialize)]
pub struct ChannelPlan {
    /// Local or gathered.
    pub transport: Transport,
    /// Why, with the figures (in JSON, its text).
    pub why: ChannelReason,
}

/// What one object gets this frame, and why.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ObjectPlan {
    /// Per channel, its reduced albedo where `material.model` gives it single scattering
    /// between points (glsl/beam_gather.comp overwrites the dipole's exitance there).
    pub single: [Option<f64>; 3],
    /// Where `material.model = "transport"`: whether its kernel scales the dipole.
    pub transport: Option<crate::scene::needs::KernelState>,
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
    /// From which lights, when it is splatted.
    pub splat_lights: SplatLights,
    /// Whether the environment's part an earlier splat kept for its samples is still current
    /// this frame (nothing since changed the environment, the geometry or its material).
    #[serde(skip)]
    pub environment_kept: bool,
    /// Its exitance is gathered this frame.
    pub gather: bool,
    /// Which of its receivers, when it is gathered.
    pub receivers: ReceiverScope,
    /// Of the receivers at its level, how many an eye may see and how many there are, where
    /// the caller counted them on the host (`receiver_view::seen_receivers`; `translucent plan`
    /// does); `None` otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub receivers_seen: Option<[usize; 2]>,
    /// Of the receivers at its level, how many a frame of change gathers besides those an eye
    /// may see because they lie in a patch the seen ones' transport kernel blends
    /// (`receiver_view::kernel_gathered`), where the caller counted them; `None` otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub receivers_for_kernel: Option<usize>,
    /// Why it is (or is not) splatted and gathered (`splat` and `gather` follow from it).
    pub why: ObjectReason,
    /// Whether its gathered exitance still needs recomputing after this frame (lights or its
    /// material changed and it was not gathered).
    pub stale_after: bool,
    /// The level of detail it is drawn, shadowed and gathered at (0: the whole mesh;
    /// `choose_level`).
    pub level: usize,
    /// Why that level, with the figures.
    pub level_why: LevelReason,
    /// Its sample count and the per-vertex error predicted for it (`scene::accuracy`;
    /// translucent objects only).
    pub density: Option<crate::scene::accuracy::Density>,
    /// Which model each channel takes, why, and the error predicted for it against the light
    /// (`scene::model_choice`; translucent objects only).
    pub model: Option<crate::scene::model_choice::ModelChoice>,
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
    pub passes: Vec<(Pass, PassReason)>,
    /// Passes left out, each with why: their last results are reused, or the scene does not need
    /// them.
    pub skipped: Vec<(Pass, SkipReason)>,
    /// When only one light's shadow maps are redrawn: that scene light; `None` redraws all.
    pub shadow_light: Option<usize>,
    /// Per object, in scene order (empty in a plan made by hand: every object runs).
    pub objects: Vec<ObjectPlan>,
    /// Shading looks each key light's shadow up with one bilinear tap instead of four (a 3x3
    /// texel tent): a texel is small on screen, so the tent's softening is below a pixel or
    /// two (`SHADOW_ONE_TAP_PIXELS`). False in a plan made by hand.
    pub one_tap_shadows: bool,
    /// Why that filter, with the figures (`None` without shadows, and in a plan made by hand).
    pub shadow_filter: Option<ShadowFilter>,
    /// Terms of the shading pass left out (`shade::TERM_*` bits), to measure what each costs
    /// (the benchmark's `terms` section); 0, every term, in any plan the planner makes.
    pub skip_terms: u32,
    /// Shading culls the faces no ray from the eye reaches: the inner side of each surface that
    /// encloses a volume, where the near plane cuts none of it (`shade::hidden_faces`). The
    /// image is the same but for depth ties at silhouettes; the hidden faces are neither
    /// rasterised nor shaded. True in any plan the planner makes; the benchmark turns it off
    /// to measure what it saves.
    pub cull_hidden_faces: bool,
    /// How this frame's splat finds visibility (`render.splat_visibility`); `None` when no
    /// splat runs.
    pub splat_visibility: Option<crate::scene::SplatVisibility>,
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

    /// Which lights object `object`'s splat evaluates (all of them in a plan made by hand).
    pub fn splat_lights(&self, object: usize) -> SplatLights {
        self.objects.get(object).map_or(SplatLights::All, |o| o.splat_lights)
    }

    /// Which of object `object`'s receivers the gather recomputes (every one in a plan made by
    /// hand).
    pub fn receivers(&self, object: usize) -> ReceiverScope {
        self.objects.get(object).map_or(ReceiverScope::Every { why: EveryReason::Asked }, |o| o.receivers)
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
        fn list<R: fmt::Display>(v: &[(Pass, R)]) -> Vec<serde_json::Value> {
            v.iter().map(|(p, why)| serde_json::json!({"pass": p.name(), "why": why.to_string()})).collect()
        }
        serde_json::json!({
            "change": self.change.map(|c| c.to_string()),
            "passes": list(&self.passes),
            "skipped": list(&self.skipped),
            "shadow_light": self.shadow_light,
            "one_tap_shadows": self.one_tap_shadows,
            "cull_hidden_faces": self.cull_hidden_faces,
            "shadow_filter_why": self.shadow_filter.map_or_else(String::new, |f| f.to_string()),
            "splat_visibility": self.splat_visibility.map(|v| v.name()),
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
        if let Some(filter) = &self.shadow_filter {
            writeln!(f, "  shadow filter: {filter}")?;
        }
        if let Some(v) = self.splat_visibility {
            writeln!(f, "  splat visibility: {v}: {}", v.why())?;
        }
        for o in self.objects.iter().filter(|o| !o.channels.is_empty() || o.level > 0) {
            writeln!(f, "  object {} ({}): {}", o.object, o.name, o.why)?;
            if o.splat && o.splat_lights == SplatLights::KeyLights {
                writeln!(f, "    splat: key lights only, the environment's part kept from an earlier frame")?;
            }
            writeln!(f, "    level {}: {}", o.level, o.level_why)?;
            if o.gather {
                write!(f, "    gathers {}", o.receivers)?;
                match (o.receivers, o.receivers_seen) {
                    (ReceiverScope::VisibleFirst { sweep: Some(s), .. }, Some([_, of])) => {
                        writeln!(f, ": {} of the level's {of} receivers in the chunk", s.range(of as u32)[1])?
                    }
                    (_, Some([seen, of])) => {
                        write!(f, ": {seen} of the level's {of} may be seen")?;
                        match o.receivers_for_kernel {
                            Some(more) => writeln!(f, ", and {more} more in the patches their kernel blends")?,
                            None => writeln!(f)?,
                        }
                    }
                    (_, None) => writeln!(f)?,
                }
            }
            if let Some(d) = &o.density {
                writeln!(f, "    {d}")?;
            }
            if let Some(m) = &o.model {
                writeln!(f, "    models: {m}")?;
            }
            if let (Some(d), Some(m)) = (&o.density, &o.model) {
                let total = m.total(d.predicted.map(|c| c.error));
                let pct = |e: Option<f64>| e.map_or("not predicted".to_string(), |e| format!("{:.3}%", 100.0 * e));
                let [r, g, b] = total.map(pct);
                writeln!(f, "    predicted total error against the light: R {r}, G {g}, B {b}")?;
            }
            for (c, ch) in ["R", "G", "B"].iter().zip(&o.channels) {
                let t = match ch.transport {
                    Transport::Local => "local ",
                    Transport::Gather => "gather",
                };
                writeln!(f, "    {c} {t} {}", ch.why)?;
            }
            if let Some(t) = o.transport {
                writeln!(f, "    {t}")?;
            }
            for (c, alpha) in ["R", "G", "B"].iter().zip(o.single) {
                let Some(alpha) = alpha else { continue };
                let why = if alpha < crate::optics::beam_single::ALBEDO_BELOW {
                    "under 0.3, where most light leaves after one scattering and the dipole reads low (docs/optics.md)"
                } else {
                    "material.model = \"single\" asks for it in every channel"
                };
                writeln!(
                    f,
                    "    {c} single scattering between points, after the gather: reduced albedo {alpha:.3}, {why}"
                )?;
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
    pub fn of_camera(camera: &crate::render::camera::CameraView, height: u32) -> View {
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

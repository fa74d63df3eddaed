//! Why the planner decided what it did: one type per kind of decision, carrying the figures that
//! decided it. They become text only through `Display` (`--explain`, `translucent plan` and its
//! JSON, where each is the `why` string docs/PLAN.md names).

use super::{LOCAL_SPACING, LOD_EDGE_PIXELS, LOD_ERROR_PIXELS, SHADOW_ONE_TAP_PIXELS, Transport};
use std::fmt;

/// Why a pass runs this frame.
#[derive(Clone, Debug, PartialEq)]
pub enum PassReason {
    /// Shadow: one light moved; only its shadow maps are redrawn.
    OneLightMoved,
    /// Shadow: an object's geometry moved; every shadow map is stale.
    GeometryMoved,
    /// Shadow: the lights changed; every shadow map is stale.
    LightsChanged,
    /// Vertex light: the environment or the geometry changed.
    SkyLightStale,
    /// Splat: these objects' sample irradiance is stale.
    SampleIrradianceStale {
        /// The objects splatted, in scene order.
        objects: Vec<usize>,
    },
    /// Gather (vertex or sparse): these objects' exitance is stale.
    ExitanceStale {
        /// The objects gathered, in scene order.
        objects: Vec<usize>,
    },
    /// Gather (per pixel): redone every frame for the pixels in view.
    PixelGather {
        /// The objects whose pixels are gathered, in scene order.
        objects: Vec<usize>,
    },
    /// Shade: every frame draws the view.
    DrawsView,
    /// Shade, before the pixel gather: every frame draws the view and each pixel's surface.
    DrawsViewAndSurfaces,
    /// Tonemap: every frame's HDR image is tone-mapped.
    ToneMapsEveryFrame,
}

/// Why a pass is left out this frame: its last results are reused, or the scene does not need it.
#[derive(Clone, Debug, PartialEq)]
pub enum SkipReason {
    /// Shadow, after one light moved: that light casts no shadow.
    MovedLightCastsNoShadow,
    /// Shadow, after one light moved: the scene has no shadow maps.
    NoShadowCastingLight,
    /// Shadow, after any other change: the scene has no shadow maps.
    NoShadowCaster,
    /// Shadow: lights and geometry unchanged.
    ShadowsCurrent,
    /// Vertex light: the environment and geometry are unchanged.
    SkyLightCurrent,
    /// Vertex light: the scene has no environment light.
    NoEnvironment,
    /// Splat or gather: the scene has no translucent object.
    NoTranslucentObject,
    /// Splat: no object's sample irradiance is stale (each object's plan says why).
    SampleIrradianceCurrent,
    /// Gather: no object needs a gather (each object's plan says why).
    ExitanceCurrent,
    /// Tonemap: a host target, which the host tone-maps.
    HostToneMaps,
}

/// The figures one channel's choice weighs (scene units; `Dipole` and `ObjectFacts`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelFigures {
    /// RMS radius of the profile, `r`.
    pub profile_radius: f64,
    /// `1 / sigma_tr`.
    pub diffusion_length: f64,
    /// Height of the virtual source.
    pub z_v: f64,
    /// Mean distance between the object's samples, `s`.
    pub sample_spacing: f64,
    /// Mean edge of the whole mesh.
    pub vertex_spacing: f64,
    /// Pixel footprint at the object's nearest point, `p` (0 out of view).
    pub pixel: f64,
}

/// Why a channel is local or gathered (the rules in `choose`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChannelReason {
    /// `render.transport` forces every channel this way.
    Forced {
        /// The transport forced.
        transport: Transport,
        /// The figures, for the record.
        figures: ChannelFigures,
    },
    /// Gathered: the profile is wider than the object's bounding radius.
    WiderThanObject {
        /// The object's bounding radius.
        object_radius: f32,
        /// The figures.
        figures: ChannelFigures,
    },
    /// Local: `r <= LOCAL_PIXELS p`.
    NarrowerThanPixel {
        /// The figures.
        figures: ChannelFigures,
    },
    /// Local: `LOCAL_SPACING r <= s`.
    SamplesTooSparse {
        /// The figures.
        figures: ChannelFigures,
    },
    /// Gathered: the blur spans pixels and the samples resolve it.
    Resolved {
        /// The figures.
        figures: ChannelFigures,
    },
}

impl ChannelReason {
    /// The figures behind the choice.
    pub fn figures(&self) -> &ChannelFigures {
        match self {
            ChannelReason::Forced { figures, .. }
            | ChannelReason::WiderThanObject { figures, .. }
            | ChannelReason::NarrowerThanPixel { figures }
            | ChannelReason::SamplesTooSparse { figures }
            | ChannelReason::Resolved { figures } => figures,
        }
    }
}

/// Why an object is (or is not) splatted and gathered this frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObjectReason {
    /// Opaque: nothing to splat or gather.
    Opaque,
    /// Every channel is local.
    AllLocal,
    /// Outside the view frustum: waits, stale, until it is seen.
    OutOfView,
    /// Its material changed (and the lights did not): same samples, splat and gather.
    MaterialChanged,
    /// Its geometry changed: resampled, splat and gather.
    GeometryChanged,
    /// The lights changed: splat and gather.
    LightsChanged,
    /// Back in view, stale since lights or its material changed: splat and gather.
    InViewAgain,
    /// The pixel gather redoes the pixels in view every frame; the samples' irradiance is reused.
    PixelGather,
    /// Drawn at a finer level than the last gather ran at: its vertices gathered again.
    FinerLevel {
        /// The level drawn this frame.
        level: usize,
    },
    /// Unchanged since its last gather, which left receivers no eye ray reached for later:
    /// this frame's chunk of them gathered (`receivers::SWEEP_FRAMES`), sample irradiance and
    /// the hierarchy's power reused.
    Sweeping {
        /// This frame's chunk, from 0.
        chunk: u32,
        /// Chunks in the sweep.
        of: u32,
    },
    /// Lights and material unchanged: the exitance is reused.
    Unchanged,
}

impl ObjectReason {
    /// Whether the object is splatted, and whether it is gathered, for this reason.
    pub fn splat_and_gather(self) -> (bool, bool) {
        use ObjectReason::*;
        match self {
            Opaque | AllLocal | OutOfView | Unchanged => (false, false),
            MaterialChanged | GeometryChanged | LightsChanged | InViewAgain => (true, true),
            PixelGather | FinerLevel { .. } | Sweeping { .. } => (false, true),
        }
    }
}

/// Why an object is drawn, shadowed and gathered at its level of detail (`choose_level`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LevelReason {
    /// The object has one level: drawn whole.
    OneLevel,
    /// Out of view: its coarsest level.
    OutOfView,
    /// The coarsest level within `LOD_EDGE_PIXELS` and `LOD_ERROR_PIXELS`.
    WithinLimits {
        /// Triangles of the level.
        triangles: usize,
        /// Triangles of the whole mesh.
        whole_triangles: usize,
        /// Vertices the level's triangles use.
        vertices: usize,
        /// Its mean edge (scene units).
        mean_edge: f64,
        /// Its distance from the whole mesh (scene units).
        error: f64,
        /// Scene units a pixel covers at the object's centre.
        pixel: f64,
    },
    /// Whole: this frame recomputes the sky light its levels were baked from.
    SkyLightRecomputed,
}

/// Shading's shadow filter and the texel size that chose it (`SHADOW_ONE_TAP_PIXELS`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowFilter {
    /// One bilinear tap (else the four-tap tent).
    pub one_tap: bool,
    /// Pixels a shadow-map texel spans at the casters' centre.
    pub texel_pixels: f64,
}

impl fmt::Display for PassReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PassReason::OneLightMoved => {
                write!(f, "one light moved: only its shadow maps are redrawn, the others are reused")
            }
            PassReason::GeometryMoved => write!(f, "geometry moved: every shadow map is stale"),
            PassReason::LightsChanged => write!(f, "lights changed: shadow maps are stale"),
            PassReason::SkyLightStale => {
                write!(f, "the environment or the geometry changed: per-vertex sky irradiance is stale")
            }
            PassReason::SampleIrradianceStale { objects } => {
                write!(f, "irradiance at the samples is stale for objects {objects:?}")
            }
            PassReason::ExitanceStale { objects } => write!(f, "exitance is stale for objects {objects:?}"),
            PassReason::PixelGather { objects } => {
                write!(f, "pixel gather: the receivers are the pixels in view of objects {objects:?}")
            }
            PassReason::DrawsView => write!(f, "every frame draws the view"),
            PassReason::DrawsViewAndSurfaces => {
                write!(f, "every frame draws the view (and, for the pixel gather, each pixel's surface)")
            }
            PassReason::ToneMapsEveryFrame => write!(f, "every frame's HDR image is tone-mapped"),
        }
    }
}

impl fmt::Display for SkipReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let nothing = "no translucent object needs";
        match self {
            SkipReason::MovedLightCastsNoShadow => write!(f, "the moved light casts no shadow: shadow maps reused"),
            SkipReason::NoShadowCastingLight => write!(f, "no shadow-casting light"),
            SkipReason::NoShadowCaster => write!(f, "no light casts a shadow onto a caster"),
            SkipReason::ShadowsCurrent => write!(f, "lights and geometry unchanged: shadow maps reused"),
            SkipReason::SkyLightCurrent => {
                write!(f, "the environment and geometry are unchanged: per-vertex sky irradiance reused")
            }
            SkipReason::NoEnvironment => write!(f, "no environment light"),
            SkipReason::NoTranslucentObject => write!(f, "no translucent object"),
            SkipReason::SampleIrradianceCurrent => {
                write!(f, "{nothing} its sample irradiance recomputed this frame (see the objects)")
            }
            SkipReason::ExitanceCurrent => write!(f, "{nothing} a gather this frame (see the objects)"),
            SkipReason::HostToneMaps => write!(f, "the host tone-maps its own target"),
        }
    }
}

impl fmt::Display for ChannelFigures {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ChannelFigures { profile_radius: r, diffusion_length, z_v, sample_spacing: s, vertex_spacing: v, pixel: p } =
            self;
        write!(
            f,
            "(profile radius {r:.3e}, diffusion length {diffusion_length:.3e}, z_v {z_v:.3e}; sample spacing {s:.3e}, \
             vertex spacing {v:.3e}, pixel {p:.3e})"
        )
    }
}

impl fmt::Display for ChannelReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.figures();
        let (r, s, p) = (n.profile_radius, n.sample_spacing, n.pixel);
        match self {
            ChannelReason::Forced { transport: Transport::Gather, .. } => {
                write!(f, "render.transport = \"gather\" {n}")
            }
            ChannelReason::Forced { transport: Transport::Local, .. } => write!(f, "render.transport = \"local\" {n}"),
            ChannelReason::WiderThanObject { object_radius, .. } => write!(
                f,
                "the profile is wider than the object (radius {object_radius:.3e}): light spreads through all of it, \
                 where the dipole's semi-infinite slab is a weak model; gathered over every sample {n}"
            ),
            ChannelReason::NarrowerThanPixel { .. } => {
                write!(f, "the profile is narrower than a pixel: its blur does not show, local {n}")
            }
            ChannelReason::SamplesTooSparse { .. } => write!(
                f,
                "the samples lie {:.1} profile radii apart (local from {LOCAL_SPACING}): the sum cannot resolve the \
                 profile, local {n}",
                s / r
            ),
            ChannelReason::Resolved { .. } => {
                write!(f, "the profile spans {:.1} pixels and the samples resolve it: gathered {n}", r / p.max(1e-30))
            }
        }
    }
}

impl fmt::Display for ObjectReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ObjectReason::Opaque => write!(f, "opaque"),
            ObjectReason::AllLocal => write!(f, "every channel local: no splat or gather"),
            ObjectReason::OutOfView => write!(
                f,
                "outside the view frustum: no splat or gather (light does not pass between objects); redone when it \
                 comes into view"
            ),
            ObjectReason::MaterialChanged => write!(f, "its material changed: same samples, new splat and gather"),
            ObjectReason::GeometryChanged => write!(f, "its geometry changed: resampled, splat and gather"),
            ObjectReason::LightsChanged => write!(f, "lights changed: splat and gather"),
            ObjectReason::InViewAgain => {
                write!(f, "in view again after lights or its material changed: splat and gather")
            }
            ObjectReason::PixelGather => {
                write!(f, "pixel gather: redone for the pixels in view every frame, sample irradiance reused")
            }
            ObjectReason::FinerLevel { level } => write!(
                f,
                "level {level} is finer than the last gathered: its vertices gathered, sample irradiance reused"
            ),
            ObjectReason::Sweeping { chunk, of } => write!(
                f,
                "unchanged since its last gather: chunk {} of {of} of the receivers it left for later gathered, \
                 with any stale receiver that came into view",
                chunk + 1
            ),
            ObjectReason::Unchanged => {
                write!(f, "lights and material unchanged: exitance is view-independent, reused")
            }
        }
    }
}

impl fmt::Display for LevelReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LevelReason::OneLevel => {
                write!(f, "drawn whole (one level: render.level_of_detail off, or per-vertex sky light)")
            }
            LevelReason::OutOfView => {
                write!(f, "out of view: its coarsest level (clipped away; shadow maps choose their own)")
            }
            // A camera at the object's centre (inside it) sees a pixel span no distance there.
            LevelReason::WithinLimits { triangles, whole_triangles, vertices, pixel, .. } if *pixel <= 0.0 => write!(
                f,
                "{triangles} of {whole_triangles} triangles, {vertices} vertices: the camera is inside the object, at \
                 its centre, where a pixel spans no distance, so no simplification is small enough"
            ),
            LevelReason::WithinLimits { triangles, whole_triangles, vertices, mean_edge, error, pixel } => write!(
                f,
                "{triangles} of {whole_triangles} triangles, {vertices} vertices: edges {:.2} px, error {:.2} px at \
                 {pixel:.3e} units/px (limits {LOD_EDGE_PIXELS}, {LOD_ERROR_PIXELS})",
                mean_edge / pixel,
                error / pixel,
            ),
            LevelReason::SkyLightRecomputed => {
                write!(f, "whole: this frame recomputes the sky light its levels were baked from")
            }
        }
    }
}

impl fmt::Display for ShadowFilter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !self.texel_pixels.is_finite() {
            // The camera at the casters' centre, inside them: a pixel there spans no distance.
            return write!(f, "four-tap tent: the camera is at the shadow casters' centre, inside them");
        }
        write!(
            f,
            "{}: a shadow-map texel spans {:.2} px at the casters' centre (one tap up to {SHADOW_ONE_TAP_PIXELS})",
            if self.one_tap { "one bilinear tap" } else { "four-tap tent" },
            self.texel_pixels
        )
    }
}

/// In JSON a reason is its text (the `why` strings of docs/PLAN.md).
macro_rules! serialize_as_text {
    ($($t:ty),*) => {$(
        impl serde::Serialize for $t {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                serializer.collect_str(self)
            }
        }
    )*};
}
serialize_as_text!(PassReason, SkipReason, ChannelReason, ObjectReason, LevelReason, ShadowFilter);

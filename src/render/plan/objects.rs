//! The rules for one object: its level of detail, each channel's transport, and whether it is
//! splatted and gathered this frame.

use super::frame::Frame;
use super::receivers::{ReceiverScope, SWEEP_FRAMES, Sweep};
use super::{
    Change, ChannelFigures, ChannelPlan, ChannelReason, LOCAL_PIXELS, LOCAL_SPACING, LOD_EDGE_PIXELS, LOD_ERROR_PIXELS,
    LevelReason, ObjectPlan, ObjectReason, SplatLights, Transport,
};
use crate::scene::TransportMode;
use crate::scene::needs::{LevelFacts, ObjectFacts};
use glam::Vec3;

/// The coarsest of `facts.levels` whose mean edge and distance from the full mesh stay within
/// `LOD_EDGE_PIXELS` and `LOD_ERROR_PIXELS` pixels of footprint `footprint` (scene units per
/// pixel at the object's centre); out of view (`None`), the coarsest level (its draw is clipped
/// away, and shadow maps choose their own level, `GpuScene::casters`). Returns the level and why.
pub fn choose_level(facts: &ObjectFacts, footprint: Option<f64>) -> (usize, LevelReason) {
    let last = facts.levels.len().saturating_sub(1);
    if last == 0 {
        return (0, LevelReason::OneLevel);
    }
    let Some(px) = footprint else {
        return (last, LevelReason::OutOfView);
    };
    // A level simplified around the vertices where its values vary keeps them wherever they
    // vary: only its distance from the whole mesh limits it.
    let fits = |l: &LevelFacts| (l.locked || l.mean_edge <= LOD_EDGE_PIXELS * px) && l.error <= LOD_ERROR_PIXELS * px;
    let level = (0..=last).rev().find(|&i| fits(&facts.levels[i])).unwrap_or(0);
    let l = &facts.levels[level];
    let why = LevelReason::WithinLimits {
        triangles: l.triangles,
        whole_triangles: facts.levels[0].triangles,
        vertices: l.vertices,
        mean_edge: l.mean_edge,
        error: l.error,
        pixel: px,
    };
    (level, why)
}

/// The choice for each channel of a translucent object seen with pixel footprint `footprint`
/// (`None`: out of view, judged by its samples and mesh alone), under `mode`.
pub fn choose(facts: &ObjectFacts, footprint: Option<f64>, mode: TransportMode) -> Vec<ChannelPlan> {
    let Some(channels) = &facts.channels else { return Vec::new() };
    let (s, p) = (facts.sample_spacing, footprint.unwrap_or(0.0));
    channels
        .iter()
        .map(|c| {
            let r = c.profile_radius;
            let figures = ChannelFigures {
                profile_radius: r,
                diffusion_length: c.diffusion_length,
                z_v: c.z_v,
                sample_spacing: s,
                vertex_spacing: facts.vertex_spacing,
                pixel: p,
            };
            let (transport, why) = match mode {
                TransportMode::Gather => {
                    (Transport::Gather, ChannelReason::Forced { transport: Transport::Gather, figures })
                }
                TransportMode::Local => {
                    (Transport::Local, ChannelReason::Forced { transport: Transport::Local, figures })
                }
                TransportMode::Auto if r > facts.radius as f64 => {
                    (Transport::Gather, ChannelReason::WiderThanObject { object_radius: facts.radius, figures })
                }
                TransportMode::Auto if r <= LOCAL_PIXELS * p => {
                    (Transport::Local, ChannelReason::NarrowerThanPixel { figures })
                }
                TransportMode::Auto if LOCAL_SPACING * r <= s => {
                    (Transport::Local, ChannelReason::SamplesTooSparse { figures })
                }
                TransportMode::Auto => (Transport::Gather, ChannelReason::Resolved { figures }),
            };
            ChannelPlan { transport, why }
        })
        .collect()
}

/// What earlier frames left for one object (`Planner`).
#[derive(Clone, Copy, Debug)]
pub(super) struct ObjectHistory {
    /// Its gathered exitance was already out of date.
    pub stale: bool,
    /// The finest level of detail whose vertices hold its current exitance (`usize::MAX`: none;
    /// `None`: not known, as none).
    pub gathered: Option<usize>,
    /// The environment's part of its samples' irradiance, kept on the GPU, is current.
    pub environment_kept: bool,
    /// Its splat generation: the last one its visible-first gathers marked receivers with.
    pub generation: u32,
    /// The sweep its last visible-first gather left, if it has not finished.
    pub sweep: Option<SweepState>,
}

/// A sweep still to run over an object's receivers (`receivers::Sweep`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SweepState {
    /// The next chunk.
    pub next: u32,
    /// The level of detail whose receivers it sweeps: drawn at another, it starts again there.
    pub level: usize,
}

impl Frame<'_> {
    /// The plan for object `i`, with `facts`, after `history`.
    pub(super) fn object(&self, i: usize, facts: &ObjectFacts, history: ObjectHistory) -> ObjectPlan {
        let (view, change) = (self.view, self.change);
        let center = Vec3::from(facts.center);
        let in_view = view.sees(center, facts.radius);
        let nearest = (center.distance(view.eye) - facts.radius).max(0.0) as f64;
        let footprint = in_view.then(|| view.pixel_footprint(nearest));
        let channels = choose(facts, footprint, self.needs.transport);
        let (level, level_why) = self.level(facts, in_view);
        let stale_now = history.stale || self.lights_stale || change == Change::Material(i);
        let finer = history.gathered.is_some_and(|g| level < g);
        // A sweep left unfinished goes on at the level drawn, from its first chunk at a new one.
        let sweep = history.sweep.map(|s| Sweep { chunk: if s.level == level { s.next } else { 0 }, of: SWEEP_FRAMES });
        let why = self.work(i, &channels, in_view, stale_now, finer.then_some(level), sweep);
        let (splat, gather) = why.splat_and_gather();
        let (policy, mode) = (self.needs.receivers, self.needs.gather);
        let receivers = match why {
            ObjectReason::Sweeping { chunk, of } => {
                ReceiverScope::of(facts, policy, mode, history.generation, false, Some(Sweep { chunk, of }))
            }
            // A gather that aggregates the splat makes a new generation; no gather, none.
            _ if gather => {
                ReceiverScope::of(facts, policy, mode, history.generation.wrapping_add(1).max(1), true, None)
            }
            _ => ReceiverScope::of(facts, policy, mode, history.generation, false, None),
        };
        let kept = history.environment_kept && !self.environment_stale && change != Change::Material(i);
        let splat_lights =
            if splat && kept && self.needs.environment.is_some() { SplatLights::KeyLights } else { SplatLights::All };
        ObjectPlan {
            object: i,
            single: facts.single,
            transport: facts.transport,
            name: facts.name.clone(),
            in_view,
            pixel_footprint: footprint,
            stale_after: !channels.is_empty() && stale_now && !gather,
            channels,
            splat,
            splat_lights,
            environment_kept: kept,
            gather,
            receivers,
            receivers_seen: None,
            receivers_for_kernel: None,
            why,
            level,
            level_why,
            density: facts.density.clone(),
            model: facts.model.clone(),
        }
    }

    /// The level an object is drawn at: `choose_level`, judged at the centre's distance (the
    /// bounding sphere's nearest point lies well in front of most of the surface, and would keep
    /// far more triangles than pixels), or the whole mesh on a frame that recomputes the sky
    /// light its levels were baked from.
    fn level(&self, facts: &ObjectFacts, in_view: bool) -> (usize, LevelReason) {
        if self.needs.environment.is_some() && self.environment_stale && facts.levels.iter().any(|l| l.locked) {
            return (0, LevelReason::SkyLightRecomputed);
        }
        let center = Vec3::from(facts.center);
        choose_level(facts, in_view.then(|| self.view.pixel_footprint(center.distance(self.view.eye) as f64)))
    }

    /// Whether object `i`, with `channels`, is splatted and gathered, and why: `stale_now`, its
    /// exitance is out of date; `finer`, the level it is drawn at when that is finer than the
    /// last gathered; `sweep`, the chunk its last gather left for this frame.
    fn work(
        &self,
        i: usize,
        channels: &[ChannelPlan],
        in_view: bool,
        stale_now: bool,
        finer: Option<usize>,
        sweep: Option<Sweep>,
    ) -> ObjectReason {
        if channels.is_empty() {
            ObjectReason::Opaque
        } else if channels.iter().all(|c| c.transport == Transport::Local) {
            ObjectReason::AllLocal
        } else if !in_view {
            ObjectReason::OutOfView
        } else if stale_now {
            match self.change {
                Change::Material(m) if m == i && !self.lights_stale => ObjectReason::MaterialChanged,
                Change::Geometry(m) if m == i => ObjectReason::GeometryChanged,
                _ if self.lights_stale => ObjectReason::LightsChanged,
                _ => ObjectReason::InViewAgain,
            }
        } else if self.needs.pixel_gather {
            ObjectReason::PixelGather
        } else if let Some(level) = finer {
            ObjectReason::FinerLevel { level }
        } else if let Some(Sweep { chunk, of }) = sweep {
            ObjectReason::Sweeping { chunk, of }
        } else {
            ObjectReason::Unchanged
        }
    }
}

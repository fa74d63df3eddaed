//! The renderer's models side by side (`study --physics --render-models dipole,auto,transport`).
//!
//! The scene is swept once per `material.model`. Each model's rows are measured against that
//! model's own exact exitance (the discretisation error) and all of them against the one
//! radiative-transfer reference (the total error, against the light), so the Pareto front
//! against the light spans the models, each with its precompute.

use super::report::Summary;
use super::{Event, Step, StudyError};
use crate::reference::directional::FINENESS;
use crate::reference::rte_mesh::KernelSettings;
use crate::reference::transport_cache;
use crate::reference::truth::Truth;
use crate::scene::ScatteringModel;
use crate::scene::build::{PreparedScene, ResolvedMaterial};
use crate::scene::model_choice::ChannelModel;
use std::path::Path;

/// The scene as one model renders it, and what that model's rows are measured against.
#[derive(Clone, Debug)]
pub struct RenderModel {
    /// The model forced on every translucent material; `None`: each material's own.
    pub forced: Option<ScatteringModel>,
    /// The scene with that model, its channels' models chosen again
    /// (`PreparedObject::choose_model`) and its kernels attached.
    pub base: PreparedScene,
    /// The model's exact exitance per object, vertex and channel: the dipole's exact integral,
    /// that scaled by the object's kernel (`transport_cache::model_exitance`), or single
    /// scattering between points (`reference::single::between_points`), as the channel takes.
    pub truth: Truth,
    /// Wall time of its kernels' walks, seconds (0 without a kernel; the recorded time where a
    /// kernel came from the cache).
    pub precompute_s: f64,
}

impl RenderModel {
    /// The name rows and legends carry: the forced model's, or empty for the scene's own.
    pub fn name(&self) -> &'static str {
        self.forced.map_or("", ScatteringModel::name)
    }
}

/// Single scattering between points over a scene (`reference::single::between_points`, a long
/// integral), computed at most once however many models of a study read it: it depends on the
/// geometry, media and lights alone, not on the model.
pub struct BetweenPoints<'a> {
    base: &'a PreparedScene,
    exitance: std::cell::OnceCell<Vec<Vec<[f64; 3]>>>,
    progress: &'a (dyn Fn(Event) + Sync),
}

impl<'a> BetweenPoints<'a> {
    /// Over `base`, not computed yet; `progress` hears when it starts.
    pub fn new(base: &'a PreparedScene, progress: &'a (dyn Fn(Event) + Sync)) -> BetweenPoints<'a> {
        BetweenPoints { base, exitance: std::cell::OnceCell::new(), progress }
    }

    /// Per object, vertex and channel; computed on the first call.
    pub fn get(&self) -> &[Vec<[f64; 3]>] {
        self.exitance.get_or_init(|| {
            (self.progress)(Event::Step(Step::BetweenPoints));
            crate::reference::single::between_points(self.base, FINENESS)
        })
    }
}

/// `base` under each of `forced` (`None`: as its materials say), against `dipole`, the
/// dipole's exact integral over it, and `single`, single scattering between points over it;
/// kernels are read from or walked into `dir`, and `progress` hears of their walks.
pub fn prepare(
    base: &PreparedScene,
    forced: &[Option<ScatteringModel>],
    (dipole, single): (&Truth, &BetweenPoints<'_>),
    dir: &Path,
    progress: &(dyn Fn(Event) + Sync),
) -> Result<Vec<RenderModel>, StudyError> {
    let mut out = Vec::new();
    for &forced in forced {
        let mut base = base.clone();
        let target = base.scene.file.render.max_error;
        for o in &mut base.objects {
            if let (Some(m), ResolvedMaterial::Translucent { model, .. }) = (forced, &mut o.material) {
                *model = m;
                o.transport = None;
                o.choose_model(target);
            }
        }
        let names: Vec<String> = base.objects.iter().map(|o| o.name.clone()).collect();
        let walk = |o: usize, done, of| progress(Event::Kernel(names[o].clone(), done, of));
        let precompute_s = transport_cache::attach(&mut base.objects, &KernelSettings::default(), dir, &walk)?;
        let truth =
            Truth { exitance: exact_exitance(&base, &dipole.exitance, single, dir, progress)?, ..dipole.clone() };
        out.push(RenderModel { forced, base, truth, precompute_s });
    }
    Ok(out)
}

/// Per object, vertex and channel, the exact exitance of the model each channel of `base`
/// takes (see [`RenderModel::truth`]); NaN where `dipole` is (off a truth's receivers).
/// `single` gives single scattering between points, read only where a channel takes it.
fn exact_exitance(
    base: &PreparedScene,
    dipole: &[Vec<[f64; 3]>],
    single: &BetweenPoints<'_>,
    dir: &Path,
    progress: &(dyn Fn(Event) + Sync),
) -> Result<Vec<Vec<[f64; 3]>>, StudyError> {
    let takes = |o: &crate::scene::build::PreparedObject, m: ChannelModel| {
        o.model.as_ref().is_some_and(|c| c.channels.iter().any(|ch| ch.takes == m))
    };
    let kernel = if base.objects.iter().any(|o| takes(o, ChannelModel::Kernel)) {
        let walk = |o: usize, done, of| progress(Event::Kernel(base.objects[o].name.clone(), done, of));
        Some(transport_cache::model_exitance(base, dipole, dir, &walk)?)
    } else {
        None
    };
    let single = base.objects.iter().any(|o| takes(o, ChannelModel::Single)).then(|| single.get());
    let mut out = dipole.to_vec();
    for (i, (o, exitance)) in base.objects.iter().zip(&mut out).enumerate() {
        let Some(choice) = &o.model else { continue };
        for (v, m) in exitance.iter_mut().enumerate() {
            for c in 0..3 {
                if m[c].is_nan() {
                    continue;
                }
                m[c] = match choice.channels[c].takes {
                    ChannelModel::Dipole => m[c],
                    ChannelModel::Kernel => kernel.as_ref().map_or(m[c], |k| k[i][v][c]),
                    ChannelModel::Single => single.map_or(m[c], |s| s[i][v][c]),
                };
            }
        }
    }
    Ok(out)
}

/// `rows` by [`Row::model`](super::report::Row::model), in the order the models were first met.
pub fn by_model(rows: &[super::report::Row]) -> Vec<(String, Vec<super::report::Row>)> {
    let mut out: Vec<(String, Vec<super::report::Row>)> = Vec::new();
    for r in rows {
        match out.iter_mut().find(|(m, _)| *m == r.model) {
            Some((_, group)) => group.push(r.clone()),
            None => out.push((r.model.clone(), vec![r.clone()])),
        }
    }
    out
}

/// The summaries with their error taken against the light ([`Summary::total`]), those without
/// one left out: what `light.png` plots and [`markdown`] ranks.
pub fn against_light(summaries: &[Summary]) -> Vec<Summary> {
    summaries.iter().filter(|s| s.total.is_finite()).map(|s| Summary { error: s.total, ..s.clone() }).collect()
}

/// [`against_light`] with each model named with its precompute, for `light.png`'s legend:
/// `transport (7.77 s precompute)`.
pub fn with_precompute(light: &[Summary]) -> Vec<Summary> {
    let name = |s: &Summary| match s.precompute_s > 0.0 {
        true => format!("{} ({} s precompute)", s.model, super::report::sig3(s.precompute_s)).trim_start().to_string(),
        false => s.model.clone(),
    };
    light.iter().map(|s| Summary { model: name(s), ..s.clone() }).collect()
}

/// study.md's section on the models against the light: per model its precompute, device
/// memory and model error, its best total error and how many of its configurations are on the
/// Pareto front of total error against frame time; then the fastest configuration within each
/// target, over every model. Empty without a total error (no `--physics`).
pub fn markdown(rows: &[super::report::Row], summaries: &[Summary]) -> String {
    use super::report::{TARGETS, fastest_meeting, pareto, percent, sig3};
    use std::fmt::Write as _;
    let light = against_light(summaries);
    if light.is_empty() {
        return String::new();
    }
    let points: Vec<(f64, f64)> = light.iter().map(|s| (s.frame_ms, s.error)).collect();
    let front = pareto(&points);
    let mut out = String::from(
        "\n## The models against the light\n\nTotal error: the renderer against the radiative-transfer \
         reference (per-vertex relative RMS, mean of r, g, b), against the median light frame (`light.png`). \
         Precompute: the wall time of the transport kernels' walks, once per mesh and medium, then cached.\n\n\
         | model | precompute | device memory | model error (r, g, b) | best total error | its frame | on the front |\n\
         |---|---:|---:|---|---:|---:|---:|\n",
    );
    for (name, group) in by_model(rows) {
        let own: Vec<usize> = (0..light.len()).filter(|&i| light[i].model == name).collect();
        let Some(&best) = own.iter().min_by(|&&a, &&b| light[a].error.total_cmp(&light[b].error)) else { continue };
        let first = &group[0];
        let mib = group.iter().map(|r| r.device_mib).fold(0.0, f64::max);
        let _ = writeln!(
            out,
            "| {} | {} s | {} MiB | {} % | {} % ({}) | {} ms | {} of {} |",
            if name.is_empty() { "the scene's own" } else { &name },
            sig3(first.precompute_s),
            sig3(mib),
            first.model_rel_rms.map(percent).join(", "),
            percent(light[best].error),
            light[best].label(),
            sig3(light[best].frame_ms),
            own.iter().filter(|&&i| front[i]).count(),
            own.len()
        );
    }
    out.push_str("\nThe fastest configuration within each target against the light:\n\n| target | configuration | total error | frame |\n|---:|---|---:|---:|\n");
    for t in TARGETS {
        let cell = fastest_meeting(&light, t).map_or("none in the sweep | | ".to_string(), |s| {
            format!("{} | {} % | {} ms", s.label(), percent(s.error), sig3(s.frame_ms))
        });
        let _ = writeln!(out, "| {} % | {cell} |", percent(t));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(model: &str, frame_ms: f64, total: f64, precompute_s: f64) -> Summary {
        Summary {
            model: model.into(),
            sampler: "turk".into(),
            samples: 100,
            gather: "vertex".into(),
            epsilon: None,
            seeds: 1,
            frame_ms,
            error: 0.5,
            error_spread: 0.0,
            flip_mean: f64::NAN,
            image_rel_rmse: f64::NAN,
            sampling_ms: 1.0,
            predicted: f64::NAN,
            predicted_worst: f64::NAN,
            error_worst: 0.5,
            total,
            precompute_s,
        }
    }

    #[test]
    fn against_the_light_a_configuration_reads_its_total_error_and_one_without_is_left_out() {
        let s = [summary("dipole", 2.0, 0.3, 0.0), summary("transport", 2.5, f64::NAN, 8.0)];
        let light = against_light(&s);
        assert_eq!(light.len(), 1);
        assert_eq!((light[0].model.as_str(), light[0].error), ("dipole", 0.3));
    }

    #[test]
    fn the_legend_names_a_model_with_its_precompute_only_where_it_has_one() {
        let s = [summary("dipole", 2.0, 0.3, 0.0), summary("transport", 2.5, 0.1, 7.773), summary("", 2.5, 0.1, 1.0)];
        let named: Vec<String> = with_precompute(&s).into_iter().map(|s| s.model).collect();
        assert_eq!(named, ["dipole", "transport (7.77 s precompute)", "(1.00 s precompute)"]);
    }
}

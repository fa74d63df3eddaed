//! The study's tables: one CSV row per configuration and seed, seed-averaged summaries, the Pareto front
//! and the Markdown write-up generated from them.
//!
//! Everything here is plain data in, text out, so the report can be rebuilt from a saved CSV without a GPU.

use std::collections::BTreeMap;
use std::fmt::Write as _;

/// One configuration and seed of the study: one CSV row.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// Scene name (commas are replaced in the CSV so the file needs no quoting).
    pub scene: String,
    /// The `material.model` forced on the scene for this row (`study --render-models`);
    /// empty (`own` in the CSV): each material's own.
    pub model: String,
    /// Wall time of the precompute this row's model needs (its transport kernels' walks),
    /// seconds; 0 without one.
    pub precompute_s: f64,
    /// The scene's own configuration (its error target's count and gather), not the sweep's.
    pub default: bool,
    /// Sample placement: `random`, `turk`, `feature` or `poisson`.
    pub sampler: String,
    /// Requested sample count (the placed count may differ slightly).
    pub samples: usize,
    /// Irradiance gather: `vertex`, `sparse`, `pixel` or `tree`.
    pub gather: String,
    /// The hierarchical gather's epsilon; `None` (an empty CSV cell) for the other gathers.
    pub epsilon: Option<f64>,
    /// Seed of the sample placement.
    pub seed: u64,
    /// CPU time to place the samples, in milliseconds.
    pub sampling_ms: f64,
    /// Median GPU time of the splat pass, in milliseconds.
    pub splat_ms: f64,
    /// Median GPU time of the gather pass, in milliseconds.
    pub gather_ms: f64,
    /// Median GPU time of the shading pass, in milliseconds.
    pub shade_ms: f64,
    /// Median GPU time of the whole frame, in milliseconds.
    pub frame_ms: f64,
    /// Device memory the configuration allocated, in MiB.
    pub device_mib: f64,
    /// Per-vertex relative RMS error against the ground truth, per channel (r, g, b).
    pub rel_rms: [f64; 3],
    /// 99th percentile of the per-vertex relative error, per channel.
    pub p99: [f64; 3],
    /// Largest per-vertex relative error, per channel.
    pub max: [f64; 3],
    /// Mean signed relative error (positive: too bright), per channel.
    pub bias: [f64; 3],
    /// Relative RMS error of the rendered image against the reference image.
    pub image_rel_rmse: f64,
    /// Mean of the FLIP error map of the rendered image against the reference image.
    pub flip_mean: f64,
    /// The error model's prediction for this row per channel (`sampling::density`, worst
    /// object; NaN where it makes none: samplers other than Turk's, the pixel gather).
    pub predicted: [f64; 3],
    /// With `--physics`, per channel: the model error, the row's model's exact exitance
    /// (`study::models`) against the radiative-transfer reference (relative RMS per vertex; the
    /// same on every row of a model). NaN without.
    pub model_rel_rms: [f64; 3],
    /// With `--physics`, per channel: the total error, the renderer against the
    /// radiative-transfer reference (relative RMS per vertex). NaN without, or for the pixel
    /// gather.
    pub total_rel_rms: [f64; 3],
    /// With `--physics`, per channel: the reference's own noise, the RMS over lit vertices of
    /// its relative standard error. NaN without.
    pub rte_noise: [f64; 3],
}

/// CSV header, in column order; the single source for it, so the writer and any reader agree.
pub const COLUMNS: &[&str] = &[
    "scene",
    "configuration",
    "sampler",
    "samples",
    "gather",
    "epsilon",
    "seed",
    "sampling_ms",
    "splat_ms",
    "gather_ms",
    "shade_ms",
    "frame_ms",
    "device_mib",
    "rel_rms_r",
    "rel_rms_g",
    "rel_rms_b",
    "p99_r",
    "p99_g",
    "p99_b",
    "max_r",
    "max_g",
    "max_b",
    "bias_r",
    "bias_g",
    "bias_b",
    "image_rel_rmse",
    "flip_mean",
    "predicted_r",
    "predicted_g",
    "predicted_b",
    "model_rel_rms_r",
    "model_rel_rms_g",
    "model_rel_rms_b",
    "total_rel_rms_r",
    "total_rel_rms_g",
    "total_rel_rms_b",
    "rte_noise_r",
    "rte_noise_g",
    "rte_noise_b",
    "model",
    "precompute_s",
];

/// Error targets (as fractions) the report finds the fastest configuration for.
pub const TARGETS: [f64; 4] = [0.10, 0.03, 0.01, 0.003];

/// Makes a text field safe for an unquoted CSV cell: commas and line breaks would split it.
fn csv_text(s: &str) -> String {
    s.replace([',', '\n', '\r'], ";")
}

/// The rows as CSV: the [`COLUMNS`] header, then one line per row.
///
/// Floats use Rust's shortest round-tripping form, so reading the file back loses nothing.
pub fn csv(rows: &[Row]) -> String {
    let mut out = COLUMNS.join(",");
    out.push('\n');
    for row in rows {
        let mut fields = vec![
            csv_text(&row.scene),
            (if row.default { "default" } else { "sweep" }).to_string(),
            csv_text(&row.sampler),
            row.samples.to_string(),
            csv_text(&row.gather),
            row.epsilon.map(|e| e.to_string()).unwrap_or_default(),
            row.seed.to_string(),
        ];
        fields.extend(
            [row.sampling_ms, row.splat_ms, row.gather_ms, row.shade_ms, row.frame_ms, row.device_mib]
                .iter()
                .map(f64::to_string),
        );
        for channels in [&row.rel_rms, &row.p99, &row.max, &row.bias] {
            fields.extend(channels.iter().map(f64::to_string));
        }
        fields.push(row.image_rel_rmse.to_string());
        fields.push(row.flip_mean.to_string());
        fields.extend(row.predicted.iter().map(f64::to_string));
        for channels in [&row.model_rel_rms, &row.total_rel_rms, &row.rte_noise] {
            fields.extend(channels.iter().map(f64::to_string));
        }
        // `own`: each material's own model (no `--render-models`).
        fields.push(if row.model.is_empty() { "own".to_string() } else { csv_text(&row.model) });
        fields.push(row.precompute_s.to_string());
        debug_assert_eq!(fields.len(), COLUMNS.len());
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}

/// The single error figure used for plots and targets: the mean over r, g, b of the per-vertex relative RMS
/// error.
///
/// The mean rather than the worst channel, because the channels of a translucent material differ in mean free
/// path by design and the study compares configurations, not channels; the per-channel figures stay in the CSV.
/// The pixel gather has no per-vertex exitance: its figure is the image's relative RMSE instead.
pub fn error_of(row: &Row) -> f64 {
    let vertex = row.rel_rms.iter().sum::<f64>() / 3.0;
    if vertex.is_finite() { vertex } else { row.image_rel_rmse }
}

/// The largest of three channels' values (NaN if any is NaN): what an error target bounds.
pub fn worst(channels: &[f64; 3]) -> f64 {
    if channels.iter().any(|c| c.is_nan()) { f64::NAN } else { channels.iter().copied().fold(f64::MIN, f64::max) }
}

/// Pareto optimality of (time, error) pairs: `true` where no other point is at least as good in both and
/// strictly better in one.
///
/// Points with a non-finite coordinate are never on the front and never push another point off it.
pub fn pareto(points: &[(f64, f64)]) -> Vec<bool> {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    points
        .iter()
        .map(|p| {
            finite(p)
                && !points.iter().filter(|q| finite(q)).any(|q| q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1))
        })
        .collect()
}

/// One configuration with its seeds combined.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// The model forced ([`Row::model`]; empty: the scene's own).
    pub model: String,
    /// Sample placement.
    pub sampler: String,
    /// Requested sample count.
    pub samples: usize,
    /// Irradiance gather.
    pub gather: String,
    /// The hierarchical gather's epsilon, if any.
    pub epsilon: Option<f64>,
    /// How many seeds were combined.
    pub seeds: usize,
    /// Median over seeds of the frame time, in milliseconds (the median shrugs off one slow run).
    pub frame_ms: f64,
    /// Mean over seeds of [`error_of`].
    pub error: f64,
    /// Largest minus smallest [`error_of`] over the seeds: how much the placement's randomness moves the error.
    pub error_spread: f64,
    /// Mean over seeds of the image FLIP mean.
    pub flip_mean: f64,
    /// Mean over seeds of the image relative RMS error.
    pub image_rel_rmse: f64,
    /// Mean over seeds of the CPU sample placement time, in milliseconds.
    pub sampling_ms: f64,
    /// Mean over seeds of the error model's prediction, mean of r, g, b (NaN where it makes
    /// none).
    pub predicted: f64,
    /// Mean over seeds of the prediction for the channel predicted worst: what an error target
    /// bounds, since the count is chosen for the channel that needs most.
    pub predicted_worst: f64,
    /// Mean over seeds of the measured error of the worst channel (per-vertex relative RMS).
    pub error_worst: f64,
    /// Mean over seeds of the total error against the light, mean of r, g, b
    /// ([`Row::total_rel_rms`]; NaN without `--physics`).
    pub total: f64,
    /// Mean over seeds of [`Row::precompute_s`].
    pub precompute_s: f64,
}

impl Summary {
    /// Short name of the configuration, as used in tables and plot legends.
    pub fn label(&self) -> String {
        format!(
            "{}{} {} + {}",
            self.model_prefix(),
            self.sampler,
            self.samples,
            curve_gather(&self.gather, self.epsilon)
        )
    }

    /// Name of the curve this configuration lies on: everything but the sample count.
    pub fn curve(&self) -> String {
        format!("{}{} + {}", self.model_prefix(), self.sampler, curve_gather(&self.gather, self.epsilon))
    }

    /// `transport: ` where a model was forced, else nothing.
    fn model_prefix(&self) -> String {
        if self.model.is_empty() { String::new() } else { format!("{}: ", self.model) }
    }
}

pub(crate) fn curve_gather(gather: &str, epsilon: Option<f64>) -> String {
    match epsilon {
        // The texture gather's parameter is its atlas's resolution.
        Some(r) if gather == "texture" => format!("texture {}²", param(r)),
        Some(e) => format!("{gather} ε={}", param(e)),
        None => gather.to_string(),
    }
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => values[n / 2],
        _ => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

/// Combines the rows of each configuration (sampler, samples, gather, epsilon) over their seeds, sorted by
/// (gather, sampler, samples, epsilon).
///
/// Rows of different scenes would be merged: pass one scene's rows at a time.
pub fn summarise(rows: &[Row]) -> Vec<Summary> {
    type Key = (String, String, String, usize, Option<u64>);
    let mut groups: BTreeMap<Key, Vec<&Row>> = BTreeMap::new();
    for row in rows {
        // Sort epsilon numerically: the bits of a non-negative float order like the float.
        let epsilon = row.epsilon.map(|e| e.max(0.0).to_bits());
        let key = (row.model.clone(), row.gather.clone(), sampler_label(row), row.samples, epsilon);
        groups.entry(key).or_default().push(row);
    }
    groups
        .into_values()
        .map(|group| {
            let first = group[0];
            let errors: Vec<f64> = group.iter().map(|r| error_of(r)).collect();
            let lo = errors.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = errors.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            Summary {
                model: first.model.clone(),
                sampler: sampler_label(first),
                samples: first.samples,
                gather: first.gather.clone(),
                epsilon: first.epsilon,
                seeds: group.len(),
                frame_ms: median(&mut group.iter().map(|r| r.frame_ms).collect::<Vec<_>>()),
                error: mean(errors.iter().copied()),
                error_spread: hi - lo,
                flip_mean: mean(group.iter().map(|r| r.flip_mean)),
                image_rel_rmse: mean(group.iter().map(|r| r.image_rel_rmse)),
                sampling_ms: mean(group.iter().map(|r| r.sampling_ms)),
                predicted: mean(group.iter().map(|r| r.predicted.iter().sum::<f64>() / 3.0)),
                predicted_worst: mean(group.iter().map(|r| worst(&r.predicted))),
                error_worst: mean(group.iter().map(|r| worst(&r.rel_rms))),
                total: mean(group.iter().map(|r| r.total_rel_rms.iter().sum::<f64>() / 3.0)),
                precompute_s: mean(group.iter().map(|r| r.precompute_s)),
            }
        })
        .collect()
}

/// The table of the error model's predictions against the measured errors, for every
/// configuration it predicts (none: no table).
fn predicted_against_measured(out: &mut String, summaries: &[Summary]) {
    let predicted: Vec<&Summary> = summaries.iter().filter(|s| s.predicted.is_finite()).collect();
    if predicted.is_empty() {
        return;
    }
    let _ = writeln!(out, "\n## The error model against the measurement\n");
    let _ = writeln!(
        out,
        "`sampling::density`'s prediction beside the measured error, as the mean of r, g, b and for \
         the worst channel: an error target bounds the worst channel, since one count serves all \
         three. The scene's own configuration is `default: ...` (docs/STUDY.md, \"The error model\").\n"
    );
    let _ = writeln!(
        out,
        "| configuration | predicted % (mean) | measured % (mean) | predicted % (worst channel) | measured % (worst channel) | measured / predicted (worst) |"
    );
    let _ = writeln!(out, "|---|---:|---:|---:|---:|---:|");
    for s in predicted {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} |",
            md_cell(&s.label()),
            percent(s.predicted),
            percent(s.error),
            percent(s.predicted_worst),
            percent(s.error_worst),
            sig3(s.error_worst / s.predicted_worst)
        );
    }
}

/// A row's sampler as tables and curves name it: `default: turk` for the scene's own row, so it
/// stands apart from the sweep's.
pub(crate) fn sampler_label(row: &Row) -> String {
    if row.default { format!("default: {}", row.sampler) } else { row.sampler.clone() }
}

/// The configuration with the smallest frame time whose error is at most `target`, if any.
pub fn fastest_meeting(summaries: &[Summary], target: f64) -> Option<&Summary> {
    summaries
        .iter()
        .filter(|s| s.error <= target && s.frame_ms.is_finite())
        .min_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms))
}

/// `x` to three significant digits, in plain notation for everyday magnitudes and scientific otherwise.
pub(crate) fn sig3(x: f64) -> String {
    if !x.is_finite() {
        return if x.is_nan() { "n/a".into() } else { x.to_string() };
    }
    if x == 0.0 {
        return "0".into();
    }
    // Round first so that e.g. 9.996 takes the exponent of 10.0 it rounds to.
    let rounded: f64 = format!("{x:.2e}").parse().unwrap_or(x);
    let exponent = rounded.abs().log10().floor() as i32;
    if (-3..=5).contains(&exponent) {
        let decimals = (2 - exponent).max(0) as usize;
        format!("{rounded:.decimals$}")
    } else {
        format!("{rounded:.2e}")
    }
}

pub(crate) fn percent(x: f64) -> String {
    sig3(100.0 * x)
}

/// A chosen parameter (target, epsilon) without padding zeros: these are round numbers, not measurements.
fn param(x: f64) -> String {
    let s = sig3(x);
    if s.contains('.') && !s.contains('e') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

fn target_percent(target: f64) -> String {
    param(100.0 * target)
}

pub(crate) fn md_cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// The study as a Markdown document: the fastest configuration per error target, every configuration, and a
/// short reading generated from the numbers.
pub fn markdown(title: &str, preamble: &str, summaries: &[Summary]) -> String {
    let mut out = String::new();
    // Writing to a String cannot fail; the results are ignored for brevity.
    let _ = writeln!(out, "# {title}\n");
    if !preamble.trim().is_empty() {
        let _ = writeln!(out, "{}\n", preamble.trim_end());
    }
    let _ = writeln!(
        out,
        "Error is the per-vertex relative RMS error against the ground truth, averaged over the r, g, b channels \
         and over seeds; frame time is the median over seeds of the median GPU frame time.\n"
    );

    let _ = writeln!(out, "## Fastest configuration per error target\n");
    let _ = writeln!(out, "| target | configuration | frame ms | error % |");
    let _ = writeln!(out, "|---:|---|---:|---:|");
    for target in TARGETS {
        match fastest_meeting(summaries, target) {
            Some(s) => {
                let _ = writeln!(
                    out,
                    "| {} % | {} | {} | {} |",
                    target_percent(target),
                    md_cell(&s.label()),
                    sig3(s.frame_ms),
                    percent(s.error)
                );
            }
            None => {
                let _ = writeln!(out, "| {} % | none in the sweep | | |", target_percent(target));
            }
        }
    }
    predicted_against_measured(&mut out, summaries);

    let front = pareto(&summaries.iter().map(|s| (s.frame_ms, s.error)).collect::<Vec<_>>());
    let _ = writeln!(out, "\n## Every configuration\n");
    let _ = writeln!(
        out,
        "Error is shown ± half its range over seeds. Pareto: no other configuration is both as fast and as \
         accurate.\n"
    );
    let _ = writeln!(
        out,
        "| sampler | samples | gather | epsilon | seeds | frame ms | sampling ms | error % | image rel. RMSE % | \
         FLIP mean | Pareto |"
    );
    let _ = writeln!(out, "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|:---:|");
    for (s, on_front) in summaries.iter().zip(&front) {
        let error = if s.seeds > 1 {
            format!("{} ± {}", percent(s.error), percent(0.5 * s.error_spread))
        } else {
            percent(s.error)
        };
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            md_cell(&s.sampler),
            s.samples,
            md_cell(&s.gather),
            s.epsilon.map(param).unwrap_or_default(),
            s.seeds,
            sig3(s.frame_ms),
            sig3(s.sampling_ms),
            error,
            percent(s.image_rel_rmse),
            sig3(s.flip_mean),
            if *on_front { "yes" } else { "" }
        );
    }

    let _ = writeln!(out, "\n## Reading\n");
    out.push_str(&reading(summaries));
    out
}

/// The generated prose of the "Reading" section.
fn reading(summaries: &[Summary]) -> String {
    let mut out = String::new();
    if summaries.is_empty() {
        out.push_str("The sweep has no configurations.\n");
        return out;
    }
    // Curves: everything but the sample count, points ordered by samples.
    let mut curves: BTreeMap<String, Vec<&Summary>> = BTreeMap::new();
    for s in summaries {
        curves.entry(s.curve()).or_default().push(s);
    }
    for points in curves.values_mut() {
        points.sort_by_key(|s| s.samples);
    }

    if let Some(best) = summaries.iter().filter(|s| s.error.is_finite()).min_by(|a, b| a.error.total_cmp(&b.error)) {
        let _ = writeln!(
            out,
            "- The lowest error in the sweep, {} %, is reached by the {} curve at {} samples ({} ms per frame).",
            percent(best.error),
            md_cell(&best.curve()),
            best.samples,
            sig3(best.frame_ms)
        );
    }

    let mut samplers: BTreeMap<&str, Vec<&Summary>> = BTreeMap::new();
    for s in summaries {
        samplers.entry(&s.sampler).or_default().push(s);
    }
    let _ = writeln!(out, "- Error at each sampler's largest sample count:");
    for (sampler, list) in &samplers {
        let largest = list.iter().map(|s| s.samples).max().unwrap_or(0);
        let at: Vec<String> = list
            .iter()
            .filter(|s| s.samples == largest)
            .map(|s| format!("{} {} %", md_cell(&curve_gather(&s.gather, s.epsilon)), percent(s.error)))
            .collect();
        let _ = writeln!(out, "  - {} at {largest} samples: {}.", md_cell(sampler), at.join(", "));
    }

    let mut rises = Vec::new();
    let mut checked = 0;
    for (curve, points) in &curves {
        if points.len() < 2 {
            continue;
        }
        checked += 1;
        for pair in points.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            if b.error > a.error {
                // A rise smaller than the seed-to-seed variation says little about the method.
                let noise = if b.error - a.error <= a.error_spread.max(b.error_spread) {
                    ", within the seed spread"
                } else {
                    ""
                };
                rises.push(format!(
                    "{} ({} → {} samples: {} % → {} %{noise})",
                    md_cell(curve),
                    a.samples,
                    b.samples,
                    percent(a.error),
                    percent(b.error)
                ));
            }
        }
    }
    if checked == 0 {
        let _ = writeln!(out, "- No curve has more than one sample count, so monotonicity was not checked.");
    } else if rises.is_empty() {
        let _ = writeln!(
            out,
            "- Error fell monotonically with sample count on all {checked} curves with more than one point."
        );
    } else {
        let _ = writeln!(out, "- Error did not fall monotonically with sample count on these curves:");
        for rise in rises {
            let _ = writeln!(out, "  - {rise}");
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(sampler: &str, samples: usize, gather: &str, seed: u64, frame_ms: f64, err: f64) -> Row {
        Row {
            scene: "bunny, marble".into(),
            model: String::new(),
            precompute_s: 0.0,
            sampler: sampler.into(),
            samples,
            gather: gather.into(),
            epsilon: (gather == "tree").then_some(0.25),
            seed,
            sampling_ms: 1.0,
            splat_ms: 0.1,
            gather_ms: 0.2,
            shade_ms: 0.3,
            frame_ms,
            device_mib: 12.5,
            rel_rms: [err; 3],
            p99: [2.0 * err; 3],
            max: [3.0 * err; 3],
            bias: [-0.001; 3],
            image_rel_rmse: err / 2.0,
            flip_mean: 0.01,
            default: false,
            predicted: [f64::NAN; 3],
            model_rel_rms: [f64::NAN; 3],
            total_rel_rms: [f64::NAN; 3],
            rte_noise: [f64::NAN; 3],
        }
    }

    #[test]
    fn csv_has_header_and_one_line_per_row() {
        let rows = vec![row("random", 1000, "vertex", 1, 2.0, 0.05), row("turk", 1000, "tree", 2, 3.0, 0.04)];
        let text = csv(&rows);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0], COLUMNS.join(","));
        for line in &lines {
            assert_eq!(line.split(',').count(), COLUMNS.len(), "{line}");
        }
        // No epsilon: an empty cell; the scene's comma was replaced.
        let first: Vec<&str> = lines[1].split(',').collect();
        assert_eq!(first[0], "bunny; marble");
        assert_eq!(first[COLUMNS.iter().position(|c| *c == "epsilon").unwrap()], "");
        let second: Vec<&str> = lines[2].split(',').collect();
        assert_eq!(second[COLUMNS.iter().position(|c| *c == "epsilon").unwrap()], "0.25");
        assert_eq!(second[COLUMNS.iter().position(|c| *c == "rel_rms_b").unwrap()].parse::<f64>().unwrap(), 0.04);
    }

    #[test]
    fn pareto_front() {
        let points = [(1.0, 0.5), (2.0, 0.2), (2.0, 0.3), (3.0, 0.2), (0.5, 0.9), (4.0, 0.1), (f64::NAN, 0.0)];
        assert_eq!(pareto(&points), vec![true, true, false, false, true, true, false]);
        // Duplicates beat nobody and are both kept.
        assert_eq!(pareto(&[(1.0, 1.0), (1.0, 1.0)]), vec![true, true]);
        assert!(pareto(&[]).is_empty());
    }

    #[test]
    fn summarise_averages_seeds() {
        let rows = vec![
            row("random", 1000, "vertex", 1, 2.0, 0.04),
            row("random", 1000, "vertex", 2, 4.0, 0.06),
            row("random", 1000, "vertex", 3, 3.5, 0.05),
            row("random", 500, "vertex", 1, 1.0, 0.1),
            row("poisson", 500, "tree", 1, 5.0, 0.02),
        ];
        let s = summarise(&rows);
        assert_eq!(s.len(), 3);
        // Sorted by gather, then sampler, then samples.
        assert_eq!((s[0].gather.as_str(), s[0].samples), ("tree", 500));
        assert_eq!((s[1].sampler.as_str(), s[1].samples), ("random", 500));
        let big = &s[2];
        assert_eq!((big.samples, big.seeds), (1000, 3));
        assert!((big.error - 0.05).abs() < 1e-12);
        assert!((big.error_spread - 0.02).abs() < 1e-12);
        assert_eq!(big.frame_ms, 3.5);
        assert!((big.image_rel_rmse - 0.025).abs() < 1e-12);
        assert_eq!(s[0].epsilon, Some(0.25));
    }

    #[test]
    fn fastest_meeting_picks_cheapest_within_target() {
        let rows = vec![
            row("random", 100, "vertex", 1, 1.0, 0.2),
            row("random", 1000, "vertex", 1, 3.0, 0.05),
            row("turk", 1000, "vertex", 1, 2.0, 0.02),
            row("turk", 9000, "vertex", 1, 9.0, 0.005),
        ];
        let s = summarise(&rows);
        assert_eq!(fastest_meeting(&s, 0.10).map(|s| (s.sampler.as_str(), s.samples)), Some(("turk", 1000)));
        assert_eq!(fastest_meeting(&s, 0.01).map(|s| s.samples), Some(9000));
        assert!(fastest_meeting(&s, 0.001).is_none());
    }

    #[test]
    fn markdown_reads_the_data() {
        let rows = vec![
            row("random", 100, "vertex", 1, 1.0, 0.2),
            row("random", 1000, "vertex", 1, 3.0, 0.25),
            row("turk", 1000, "vertex", 1, 2.0, 0.02),
        ];
        let doc = markdown("Study", "Preamble text.", &summarise(&rows));
        assert!(doc.starts_with("# Study\n\nPreamble text.\n"));
        assert!(doc.contains("| 3 % | turk 1000 + vertex | 2.00 | 2.00 |"), "{doc}");
        assert!(doc.contains("| 0.3 % | none in the sweep"), "{doc}");
        assert!(doc.contains("random + vertex (100 → 1000 samples: 20.0 % → 25.0 %)"), "{doc}");
    }

    #[test]
    fn three_significant_digits() {
        assert_eq!(sig3(1.23456), "1.23");
        assert_eq!(sig3(9.996), "10.0");
        assert_eq!(sig3(0.012345), "0.0123");
        assert_eq!(sig3(1234.5), "1230");
        assert_eq!(sig3(1.5e-7), "1.50e-7");
        assert_eq!(sig3(0.0), "0");
        assert_eq!(param(0.100), "0.1");
        assert_eq!(target_percent(0.003), "0.3");
        assert_eq!(param(1.5e-7), "1.50e-7");
    }
}

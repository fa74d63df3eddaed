//! `translucent study --quick` on a tiny scene, as CI runs it: every column written, the truth
//! converged, error falling as Turk's sample count doubles, and the study's per-vertex error
//! equal to one computed by hand from `render --export-exitance` and the cached truth.

mod common;

use common::{repo_path, temp_dir, text, translucent};
use std::path::Path;
use translucent::reference::truth::{LIT_FLOOR, Truth};
use translucent::study::report::COLUMNS;

/// One CSV row, column name to text.
type Row = std::collections::HashMap<String, String>;

fn csv_rows(csv: &str) -> Vec<Row> {
    let mut lines = csv.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(str::to_string).collect();
    lines.map(|l| header.iter().cloned().zip(l.split(',').map(str::to_string)).collect()).collect()
}

/// Runs `study --quick` as CI does, with an error image and the truth cached under `cache`, and
/// checks it succeeded and wrote every output file.
fn run_quick_study(scene: &str, out: &Path, cache: &Path) {
    let run = translucent(
        &[
            "study",
            scene,
            "-o",
            out.to_str().unwrap(),
            "--quick",
            "--error-image",
            "turk:400",
            "--truth-cache",
            cache.to_str().unwrap(),
        ],
        &[],
    );
    assert!(run.status.success(), "study failed:\n{}\n{}", text(&run.stdout), text(&run.stderr));
    for f in ["study.csv", "study.md", "study.png", "truth.png", "error.png"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
}

/// The study's CSV, checked to have the documented header, the scene's own row (labelled
/// `default`, first) then the quick sweep's six rows, and no empty cell (but epsilon, which
/// only some gathers have).
fn study_rows(out: &Path) -> Vec<Row> {
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    assert_eq!(csv.lines().next().unwrap().split(',').collect::<Vec<_>>(), COLUMNS);
    let rows = csv_rows(&csv);
    assert_eq!(rows.len(), 7, "{csv}");
    assert_eq!(rows[0]["configuration"], "default", "{csv}");
    assert!(rows[1..].iter().all(|r| r["configuration"] == "sweep"), "{csv}");
    // The tiny scene fixes 400 Turk samples; its own row is that, with the model's prediction.
    assert_eq!((rows[0]["sampler"].as_str(), rows[0]["samples"].as_str()), ("turk", "400"));
    assert!(rows[0]["predicted"].parse::<f64>().unwrap() > 0.0, "{csv}");
    for r in &rows {
        for c in COLUMNS.iter().filter(|c| **c != "epsilon") {
            assert!(!r[*c].is_empty(), "empty {c} in {r:?}");
        }
    }
    rows
}

/// The one cached truth, checked to have converged, and the report to say so.
fn converged_truth(cache: &Path, out: &Path) -> Truth {
    let entry = std::fs::read_dir(cache).unwrap().next().unwrap().unwrap();
    let truth: Truth = serde_json::from_slice(&std::fs::read(entry.path()).unwrap()).unwrap();
    assert!(truth.converged && truth.change() < 1e-4, "levels {:?}", truth.levels);
    assert!(std::fs::read_to_string(out.join("study.md")).unwrap().contains("converged"));
    truth
}

/// Turk's rows are 100, 200 and 400 samples, and their mean relative RMS error falls at every
/// doubling.
fn assert_turk_error_falls(rows: &[Row]) {
    let error = |r: &Row| {
        ["rel_rms_r", "rel_rms_g", "rel_rms_b"].iter().map(|c| r[*c].parse::<f64>().unwrap()).sum::<f64>() / 3.0
    };
    let turk: Vec<(usize, f64)> = rows
        .iter()
        .filter(|r| r["sampler"] == "turk" && r["configuration"] == "sweep")
        .map(|r| (r["samples"].parse().unwrap(), error(r)))
        .collect();
    assert_eq!(turk.iter().map(|t| t.0).collect::<Vec<_>>(), [100, 200, 400]);
    assert!(turk.windows(2).all(|w| w[1].1 < w[0].1), "turk error does not fall: {turk:?}");
}

/// The study's turk:400 configuration rendered on its own, with its per-vertex exitance
/// exported to a PLY in `dir` and read back.
fn exported_exitance(scene: &str, dir: &Path) -> Vec<[f64; 3]> {
    let ply = dir.join("exitance.ply");
    let render = translucent(
        &[
            "render",
            scene,
            "-o",
            dir.join("r.png").to_str().unwrap(),
            "--sampler",
            "turk",
            "--samples",
            "400",
            "--gather",
            "vertex",
            "--transport",
            "gather",
            "--export-exitance",
            ply.to_str().unwrap(),
        ],
        &[],
    );
    assert!(render.status.success(), "{}", text(&render.stderr));
    let ply = std::fs::read_to_string(ply).unwrap();
    let body = ply.split("end_header\n").nth(1).unwrap();
    body.lines()
        .map(|l| {
            // The PLY holds f32s, printed shortest: parse them as f32, as written.
            let v: Vec<f64> = l.split_whitespace().map(|x| f64::from(x.parse::<f32>().unwrap())).collect();
            [v[3], v[4], v[5]]
        })
        .collect()
}

/// The study's turk:400 relative RMS error per channel equals one computed by hand from the
/// exported exitance against the truth, over the vertices the study counts as lit.
fn assert_error_matches_by_hand(rows: &[Row], truth: &Truth, exported: &[[f64; 3]]) {
    let t = &truth.exitance[0];
    assert_eq!(exported.len(), t.len());
    let row =
        rows.iter().find(|r| r["sampler"] == "turk" && r["samples"] == "400" && r["configuration"] == "sweep").unwrap();
    for (c, name) in ["rel_rms_r", "rel_rms_g", "rel_rms_b"].iter().enumerate() {
        let floor = LIT_FLOOR * t.iter().map(|m| m[c]).fold(0.0, f64::max);
        let rel: Vec<f64> = t
            .iter()
            .zip(exported)
            .filter(|(m, _)| m[c] >= floor && m[c] > 0.0)
            .map(|(m, e)| (e[c] - m[c]) / m[c])
            .collect();
        let by_hand = (rel.iter().map(|r| r * r).sum::<f64>() / rel.len() as f64).sqrt();
        let study: f64 = row[*name].parse().unwrap();
        assert!((by_hand - study).abs() <= 1e-9 * study.max(1e-12) + 1e-12, "{name}: study {study}, by hand {by_hand}");
    }
}

#[test]
fn quick_study_writes_every_column_converges_and_turk_error_falls_with_samples_and_matches_exported_exitance() {
    let dir = temp_dir("study-quick");
    let scene = repo_path("tests/scenes/study-tiny.toml");
    let scene = scene.to_str().unwrap();
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    run_quick_study(scene, &out, &cache);
    let rows = study_rows(&out);
    // The truth converged, and says so.
    let truth = converged_truth(&cache, &out);
    // Turk's error falls at every doubling.
    assert_turk_error_falls(&rows);
    // The same configuration rendered on its own, its exitance exported, its error by hand.
    let exported = exported_exitance(scene, &dir);
    assert_error_matches_by_hand(&rows, &truth, &exported);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A sweep narrowed on the command line: a bad entry stops the study before any work, naming
/// the flag and the entry, with a non-zero exit and no output folder made.
#[test]
fn study_rejects_a_bad_sweep_selection_naming_the_flag_and_writes_nothing() {
    let dir = temp_dir("study-bad-sweep");
    let out = dir.join("out");
    for (flag, value, says) in [
        ("--gathers", "hierarchical", "epsilon"),
        ("--gathers", "vertex:0.1", "only the hierarchical"),
        ("--gathers", "hierarchical:99", "epsilon must be"),
        ("--gathers", "splat", "splat"),
        ("--counts", "0", "1 to"),
        ("--samplers", "sobol", "sobol"),
        ("--truth-levels", "0", "1 to"),
        ("--truth-receivers", "10", "at least 100"),
        // --error-image names its gather as --gathers does: the hierarchical one with its epsilon.
        ("--error-image", "turk:400:hierarchical", "name the hierarchical gather's epsilon"),
        ("--error-image", "turk:400:hierarchical:99", "epsilon must be"),
        ("--error-image", "turk:401:hierarchical:0.1", "not in this sweep"),
        ("--configurations", "best", "expected default or sweep"),
        ("--max-error", "0", "must be 0.001 to 0.5"),
    ] {
        let run = translucent(&["study", "-o", out.to_str().unwrap(), flag, value], &[]);
        let err = text(&run.stderr);
        assert!(!run.status.success(), "{flag} {value} was accepted");
        assert!(err.contains(flag) && err.contains(says), "{flag} {value}: {err}");
        assert!(!out.exists(), "{flag} {value} made the output folder");
    }
    let run = translucent(
        &["study", "-o", out.to_str().unwrap(), "--truth-receivers", "500", "--error-image", "turk:400"],
        &[],
    );
    let err = text(&run.stderr);
    assert!(!run.status.success() && err.contains("--error-image") && err.contains("--truth-receivers"), "{err}");
    assert!(!out.exists(), "--error-image with --truth-receivers made the output folder");
}

#[test]
fn an_error_target_gives_a_measured_error_within_its_bounds() {
    // The study's `default` row of the tiny sphere, its count left to `render.max_error`, at
    // two targets: the planner's prediction verified against the exact integral.
    let mut scene = translucent::Scene::load(&repo_path("tests/scenes/study-tiny.toml")).unwrap();
    scene.file.sampling.count = None;
    let cache = temp_dir("study-target-cache");
    let config = translucent::study::StudyConfig {
        frames: 1,
        own: true,
        sweep: false,
        ..translucent::study::StudyConfig::quick()
    };
    let mut counts = Vec::new();
    for target in [0.1, 0.03] {
        scene.file.render.max_error = target;
        let study = common::with_gpu(|gpu| translucent::study::run(gpu, &scene, &config, &cache, &|_| {}).unwrap());
        let [row] = &study.rows[..] else { panic!("one row: {:?}", study.rows) };
        assert!(row.default);
        let measured = row.rel_rms.iter().sum::<f64>() / 3.0;
        eprintln!("target {target}: {} samples, predicted {:.4}, measured {measured:.4}", row.samples, row.predicted);
        assert!(
            (target / 3.0..=1.5 * target).contains(&measured),
            "target {target}: measured {measured} outside [{}, {}]",
            target / 3.0,
            1.5 * target
        );
        counts.push(row.samples);
    }
    assert!(counts[1] > counts[0], "a tighter target needs more samples: {counts:?}");
}

#[test]
fn the_built_in_scene_at_its_defaults_stays_within_its_error_targets_bound() {
    // The scene as `translucent` draws it with no arguments (the 1% target: about 30k Turk
    // samples, the hierarchical gather at epsilon 0.3), against the exact integral at 100
    // receivers spread over the bunny (the truth at them is the full truth's there). The bound
    // is the model's, 1.5 times the target; docs/STUDY.md has the 2,000-receiver figure.
    let cache = temp_dir("study-builtin-cache");
    let config = translucent::study::StudyConfig {
        frames: 1,
        own: true,
        sweep: false,
        truth: translucent::reference::truth::TruthOptions { receivers: Some(100), ..Default::default() },
        ..translucent::study::StudyConfig::quick()
    };
    let scene = translucent::Scene::builtin();
    let study = common::with_gpu(|gpu| translucent::study::run(gpu, &scene, &config, &cache, &|_| {}).unwrap());
    let [row] = &study.rows[..] else { panic!("one row: {:?}", study.rows) };
    let target = scene.file.render.max_error;
    let measured = row.rel_rms.iter().sum::<f64>() / 3.0;
    eprintln!(
        "built-in scene: {} samples, {} gather, predicted {:.4}, measured {measured:.4} (r, g, b {:?})",
        row.samples, row.gather, row.predicted, row.rel_rms
    );
    assert!(study.truth.converged, "the truth did not converge: {:?}", study.truth.levels);
    assert!(measured <= 1.5 * target, "measured {measured} above 1.5 x the target {target}");
}

#[test]
fn a_scene_no_light_reaches_is_refused_not_ranked() {
    // Defect 3 of the study's probe: a truth that is zero everywhere read as "converged" with
    // every configuration at 0% error.
    let dir = temp_dir("study-unlit");
    let tiny = std::fs::read_to_string(repo_path("tests/scenes/study-tiny.toml")).unwrap();
    let dark = tiny.replace("irradiance = [1.0, 1.0, 1.0]", "irradiance = [0.0, 0.0, 0.0]");
    assert_ne!(dark, tiny, "the tiny scene's light is where this test expects it");
    let scene = dir.join("dark.toml");
    std::fs::write(&scene, dark).unwrap();
    let out = dir.join("out");
    let run = translucent(
        &[
            "study",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--quick",
            "--truth-cache",
            dir.join("cache").to_str().unwrap(),
        ],
        &[],
    );
    let err = text(&run.stderr);
    assert!(!run.status.success(), "an unlit scene was studied");
    assert!(err.contains("no light reaches"), "{err}");
    assert!(!out.exists(), "the refused study made its output folder");
}

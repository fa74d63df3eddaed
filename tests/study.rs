//! `translucent study --quick` on a tiny scene, as CI runs it: every column written, the truth
//! converged, error falling as Turk's sample count doubles, and the study's per-vertex error
//! equal to one computed by hand from `render --export-exitance` and the cached truth, at a
//! sparse and a dense sample count.

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

/// `study --quick --physics` of `scene` into `out` against a 256-walk adjoint reference, the
/// truth and the reference cached under `cache`, with `models` (a `--models` or
/// `--render-models` flag and its list).
fn quick_physics_study(scene: &Path, out: &Path, cache: &Path, models: [&str; 2]) -> std::process::Output {
    let (scene, out, cache) = (scene.to_str().unwrap(), out.to_str().unwrap(), cache.to_str().unwrap());
    let args = ["study", scene, "-o", out, "--quick", "--physics", "--rte-walk", "adjoint", "--rte-photons", "256"];
    translucent(&[&args[..], &models, &["--truth-cache", cache]].concat(), &[])
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
    for c in ["predicted_r", "predicted_g", "predicted_b"] {
        assert!(rows[0][c].parse::<f64>().unwrap() > 0.0, "{c}: {csv}");
    }
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

/// The study's turk:`count` configuration rendered on its own, with its per-vertex exitance
/// exported to a PLY in `dir` and read back.
fn exported_exitance(scene: &str, dir: &Path, count: usize) -> Vec<[f64; 3]> {
    let ply = dir.join(format!("exitance-{count}.ply"));
    let render = translucent(
        &[
            "render",
            scene,
            "-o",
            dir.join("r.png").to_str().unwrap(),
            "--sampler",
            "turk",
            "--samples",
            &count.to_string(),
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

/// The study's turk:`count` relative RMS error per channel equals one computed by hand from the
/// exported exitance against the truth, over the vertices the study counts as lit.
fn assert_error_matches_by_hand(rows: &[Row], truth: &Truth, exported: &[[f64; 3]], count: usize) {
    let t = &truth.exitance[0];
    assert_eq!(exported.len(), t.len());
    let row = rows
        .iter()
        .find(|r| r["sampler"] == "turk" && r["samples"] == count.to_string() && r["configuration"] == "sweep")
        .unwrap();
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
        assert!(
            (by_hand - study).abs() <= 1e-9 * study.max(1e-12) + 1e-12,
            "turk {count}, {name}: study {study}, by hand {by_hand}"
        );
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
    // The same configuration rendered on its own, its exitance exported, its error by hand: at
    // 400 samples, and at 100, where the render and the study once placed different samples
    // (issue 47, defect 7: Turk's repulsion is chaotic in the last bits, and the two paths
    // sampled the mesh at different scales until samples were placed in the object's frame).
    for count in [100, 400] {
        let exported = exported_exitance(scene, &dir, count);
        assert_error_matches_by_hand(&rows, &truth, &exported, count);
    }
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
        // The radiative-transfer reference's budget is --physics's.
        ("--rte-photons", "1000", "only with --physics"),
        ("--rte-stderr", "0.01", "only with --physics"),
        ("--rte-seconds", "5", "only with --physics"),
        ("--rte-walk", "photons", "only with --physics"),
        ("--rte-receivers", "100", "only with --physics"),
        ("--models", "single", "only with --physics"),
        ("--render-models", "dipole,transport", "only with --physics"),
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
        eprintln!(
            "target {target}: {} samples, predicted {:?}, measured {:?}",
            row.samples, row.predicted, row.rel_rms
        );
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
        "built-in scene: {} samples, {} gather, predicted {:?}, measured {measured:.4} (r, g, b {:?})",
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

/// `study` on `scene` with `args` after `-o out --truth-cache cache` (each made under `dir`);
/// returns the output.
fn study_cli(dir: &Path, scene: &str, args: &[&str]) -> std::process::Output {
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    let mut all = vec!["study", scene, "-o", out.to_str().unwrap(), "--truth-cache", cache.to_str().unwrap()];
    all.extend_from_slice(args);
    translucent(&all, &[])
}

/// Exit status 1, no panic and no validation message, nothing written; returns stderr.
fn refused(dir: &Path, run: &std::process::Output) -> String {
    let stderr = text(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked") && !stderr.contains("[vulkan"), "{stderr}");
    assert!(!dir.join("out").join("study.csv").exists(), "an output was written: {stderr}");
    stderr
}

/// Issue 29, defect 4: a truth level whose estimated memory is over `--truth-memory` is refused
/// before it runs, naming the level, the estimate and the limit; no truth is cached and no
/// output written. A size that is not one is refused naming the option.
#[test]
fn a_truth_level_over_the_memory_limit_is_refused_naming_level_estimate_and_limit() {
    let dir = temp_dir("study-memory");
    let scene = repo_path("tests/scenes/study-tiny.toml");
    let run = study_cli(&dir, scene.to_str().unwrap(), &["--quick", "--truth-memory", "1M"]);
    let stderr = refused(&dir, &run);
    assert!(stderr.contains("would need about") && stderr.contains("more than the 1.0 MiB limit given"), "{stderr}");
    assert!(stderr.contains("E_t points") && stderr.contains("--truth-memory"), "{stderr}");
    let cached = std::fs::read_dir(dir.join("cache")).map_or(0, |d| d.filter(|e| e.is_ok()).count());
    assert_eq!(cached, 0, "a truth or temporary file was left in the cache");
    for size in ["lots", "0", "-1G", "4Q"] {
        let arg = format!("--truth-memory={size}");
        let stderr = refused(&dir, &study_cli(&dir, scene.to_str().unwrap(), &["--quick", &arg]));
        assert!(stderr.contains(&format!("--truth-memory {size:?}")), "{size}: {stderr}");
    }
}

/// An unusable `--truth-cache` is named, with the real problem, before the truth is computed:
/// with a memory limit that would refuse the truth's level 1 too, the folder's error is the
/// one reported. (It read `File exists (os error 17): File exists (os error 17)`, after the
/// whole truth.)
#[test]
fn an_unwritable_truth_cache_is_named_before_the_truth_is_computed() {
    let dir = temp_dir("study-cache-file");
    let scene = repo_path("tests/scenes/study-tiny.toml");
    std::fs::write(dir.join("cache"), "not a folder").unwrap();
    let run = study_cli(&dir, scene.to_str().unwrap(), &["--quick", "--truth-memory", "1M"]);
    let stderr = refused(&dir, &run);
    let cache = dir.join("cache");
    assert!(stderr.contains(&format!("{} is a file, not a folder", cache.display())), "{stderr}");
    assert!(!stderr.contains("os error 17") && !stderr.contains("level 1"), "{stderr}");
    assert_eq!(std::fs::read_to_string(&cache).unwrap(), "not a folder");
    let out = dir.join("out");
    let run = translucent(
        &["study", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--truth-cache", "/proc/translucent/truth"],
        &[],
    );
    let stderr = refused(&dir, &run);
    assert!(stderr.contains("/proc/translucent/truth") && stderr.contains("cannot make the folder"), "{stderr}");
}

/// Repeated `--samplers`, `--counts` and `--gathers` entries run once, and `hierarchical:-0` is
/// the gather at epsilon 0, written as 0.
#[test]
fn repeated_configurations_run_once_and_minus_zero_is_zero() {
    let dir = temp_dir("study-repeats");
    let scene = repo_path("tests/scenes/study-tiny.toml");
    let args = [
        "--quick",
        "--configurations",
        "sweep",
        "--samplers",
        "turk,turk",
        "--counts",
        "100,100",
        "--gathers",
        "hierarchical:-0,hierarchical:0",
    ];
    let run = study_cli(&dir, scene.to_str().unwrap(), &args);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let rows = csv_rows(&std::fs::read_to_string(dir.join("out").join("study.csv")).unwrap());
    assert_eq!(rows.len(), 1, "{rows:?}");
    assert_eq!((rows[0]["sampler"].as_str(), rows[0]["epsilon"].as_str()), ("turk", "0"), "{rows:?}");
    let md = std::fs::read_to_string(dir.join("out").join("study.md")).unwrap();
    assert!(!md.contains("-0"), "{md}");
}

/// `--samplers random` on a scene whose own sampler is turk: the scene's own row stays, and
/// the reference is timed on it rather than panicking on a sampler the filter removed.
#[test]
fn a_sampler_filter_that_leaves_out_the_scenes_own_sampler_still_times_the_reference() {
    let dir = temp_dir("study-sampler-filter");
    let scene = repo_path("tests/scenes/study-tiny.toml");
    let args = ["--quick", "--samplers", "random", "--counts", "100"];
    let run = study_cli(&dir, scene.to_str().unwrap(), &args);
    assert!(run.status.success(), "exit {:?}: {}", run.status.code(), text(&run.stderr));
    let rows = csv_rows(&std::fs::read_to_string(dir.join("out").join("study.csv")).unwrap());
    let samplers: Vec<&str> = rows.iter().map(|r| r["sampler"].as_str()).collect();
    assert!(samplers.contains(&"turk") && samplers.contains(&"random"), "{samplers:?}");
}

/// `--truth-levels` out of range: the note fits the value given.
#[test]
fn truth_levels_out_of_range_are_refused_with_a_fitting_note() {
    let dir = temp_dir("study-levels");
    let scene = repo_path("tests/scenes/study-tiny.toml");
    let stderr = refused(&dir, &study_cli(&dir, scene.to_str().unwrap(), &["--truth-levels", "100"]));
    assert!(stderr.contains("--truth-levels 100: must be 1 to") && !stderr.contains("level 0"), "{stderr}");
    let stderr = refused(&dir, &study_cli(&dir, scene.to_str().unwrap(), &["--truth-levels", "0"]));
    assert!(stderr.contains("level 0 has nothing to compare with"), "{stderr}");
}

/// SIGINT or SIGTERM while the truth is computed ends the study with status 130 and a message,
/// as `render`: no output file, no temporary, nothing in the cache.
#[test]
fn an_interrupted_study_exits_130_leaving_nothing() {
    for signal in ["-INT", "-TERM"] {
        let dir = temp_dir(&format!("study-interrupt{signal}"));
        let (out, cache) = (dir.join("out"), dir.join("cache"));
        let scene = repo_path("tests/scenes/study-env-sphere.toml");
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_translucent"))
            .args(["study", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--quick"])
            .args(["--truth-cache", cache.to_str().unwrap()])
            .env("TRANSLUCENT_VALIDATION", "1")
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // The cache folder is made just before the truth is computed.
        let start = std::time::Instant::now();
        while !cache.is_dir() {
            assert!(child.try_wait().unwrap().is_none(), "the study ended before its truth began");
            assert!(start.elapsed().as_secs() < 120, "the truth never began");
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        std::thread::sleep(std::time::Duration::from_millis(300));
        let pid = child.id().to_string();
        assert!(std::process::Command::new("kill").args([signal, &pid]).status().unwrap().success());
        let output = child.wait_with_output().unwrap();
        let stderr = text(&output.stderr);
        assert_eq!(output.status.code(), Some(130), "{signal}: {stderr}");
        assert!(stderr.contains("interrupted"), "{signal}: {stderr}");
        let left = |d: &Path| std::fs::read_dir(d).map_or(0, |d| d.count());
        assert_eq!((left(&out), left(&cache)), (0, 0), "{signal}: files left behind");
    }
}

/// The `--physics` columns of a CSV row for one error, per channel.
fn channels(row: &Row, name: &str) -> [f64; 3] {
    ["r", "g", "b"].map(|c| row[&format!("{name}_{c}")].parse::<f64>().unwrap())
}

/// Issue 26, part 4: `study --physics` on the tiny sphere with a Monte Carlo reference of a few
/// seconds. Every row has the model, discretisation and total errors and the reference's
/// noise, all finite and positive; the model error is one figure per scene; the total error
/// is within the triangle inequality's bound, `total <= model + discretisation (1 + model) +
/// 3 noise` per channel (the RMS of a sum of relative errors, the second taken against the
/// dipole, not the reference); study.md says where more samples stop paying; and a second run
/// reads the reference from the cache with the same figures.
#[test]
fn study_with_physics_splits_each_rows_error_into_model_discretisation_and_total_consistently() {
    let dir = temp_dir("study-physics");
    let scene = repo_path("tests/scenes/study-tiny.toml");
    let cache = dir.join("cache");
    let mut csvs = Vec::new();
    for pass in ["walked", "cached"] {
        let out = dir.join(format!("out-{pass}"));
        let run = quick_physics_study(&scene, &out, &cache, ["--models", "between,per-channel,transport"]);
        assert!(run.status.success(), "{pass}: {}", text(&run.stderr));
        let md = std::fs::read_to_string(out.join("study.md")).unwrap();
        assert!(md.contains("Against the physics") && md.contains("stop paying"), "{md}");
        assert!(md.contains("256 walks per receiver, "), "{md}");
        // The models beside the dipole, single scattering between points and the choice per channel among them.
        assert!(md.contains("| single scattering between points |"), "{md}");
        assert!(md.contains("| per channel: between points under albedo 0.3, else dipole |"), "{md}");
        assert!(md.contains("| transport in the mesh, light entering along the normal |"), "{md}");
        assert_eq!(md.contains("when walked, read from the cache"), pass == "cached", "{pass}: {md}");
        csvs.push(std::fs::read_to_string(out.join("study.csv")).unwrap());
    }
    assert_eq!(csvs[0].lines().next(), csvs[1].lines().next());
    let model_of = |csv: &str| csv_rows(csv).iter().map(|r| channels(r, "model_rel_rms")).collect::<Vec<_>>();
    assert_eq!(model_of(&csvs[0]), model_of(&csvs[1]), "the cached reference gave other figures");
    let rows = csv_rows(&csvs[0]);
    assert_eq!(rows.len(), 7);
    let model = channels(&rows[0], "model_rel_rms");
    for r in &rows {
        let (m, d, t, n) = (
            channels(r, "model_rel_rms"),
            channels(r, "rel_rms"),
            channels(r, "total_rel_rms"),
            channels(r, "rte_noise"),
        );
        assert_eq!(m, model, "the model error is the scene's, not the row's");
        for c in 0..3 {
            for (what, v) in [("model", m[c]), ("discretisation", d[c]), ("total", t[c]), ("noise", n[c])] {
                assert!(v.is_finite() && v > 0.0, "{what} {c}: {v} in {r:?}");
            }
            let bound = m[c] + d[c] * (1.0 + m[c]) + 3.0 * n[c];
            assert!(
                t[c] <= bound,
                "channel {c}: total {} above model {} + discretisation {} + 3 noise {}",
                t[c],
                m[c],
                d[c],
                n[c]
            );
            // And not below what the two leave when they do not cancel exactly.
            assert!(t[c] >= (m[c] - d[c] * (1.0 + m[c])).abs() - 3.0 * n[c], "channel {c}: total {} too small", t[c]);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The CI sphere (`tests/scenes/study-tiny.toml`) with `model = "transport"`, written into `dir`.
fn tiny_transport_scene(dir: &Path) -> std::path::PathBuf {
    let tiny = std::fs::read_to_string(repo_path("tests/scenes/study-tiny.toml")).unwrap();
    let scene = dir.join("tiny-transport.toml");
    std::fs::write(&scene, tiny.replace("model = \"dipole\"", "model = \"transport\"")).unwrap();
    scene
}

/// In a scene whose own model is the transport kernel, `--models kernel` applies the kernel
/// once, to the dipole's integral: its row reads what the scene's own row reads, and the dipole
/// is reported beside them (a kernel applied to the kernel's exitance read 8.7 to 14% on the
/// marble sphere, against 7.1 to 8.6% for the scene's own row). The bands of incidence carry
/// the reference's own noise.
#[test]
fn the_kernel_beside_a_scene_that_takes_it_is_applied_once_and_the_dipole_is_reported_beside_it() {
    let dir = temp_dir("study-kernel-once");
    let scene = tiny_transport_scene(&dir);
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    let run = quick_physics_study(&scene, &out, &cache, ["--models", "kernel"]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let md = std::fs::read_to_string(out.join("study.md")).unwrap();
    // The cells of the first table row of that name: the models' table comes before the bands'.
    let cells = |name: &str| {
        let prefix = format!("| {name} | ");
        let line = md.lines().find_map(|l| l.strip_prefix(&prefix));
        line.unwrap_or_else(|| panic!("no row {name:?} in {md}")).to_string()
    };
    let own = cells("dipole scaled by its transport kernel");
    assert_eq!(own, cells("transport kernel (dipole scaled per patch; between points under albedo 0.3)"), "{md}");
    assert_ne!(own, cells("dipole"), "{md}");
    assert!(md.contains("| reference noise | cos > 0.5 | "), "{md}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A study's long silent steps are reported: the kernel's walk patch by patch under the
/// object's name up to its last patch, and the truth's image before the first configuration.
#[test]
fn a_study_reports_its_kernel_walk_and_each_long_step_before_the_configurations() {
    use translucent::study::{Event, Step};
    let dir = temp_dir("study-steps");
    let scene = translucent::Scene::load(&tiny_transport_scene(&dir)).unwrap();
    let config = translucent::study::StudyConfig {
        frames: 1,
        own: true,
        sweep: false,
        ..translucent::study::StudyConfig::quick()
    };
    let events = std::sync::Mutex::new(Vec::new());
    let record = |e: Event| events.lock().unwrap().push(e);
    common::with_gpu(|gpu| translucent::study::run(gpu, &scene, &config, &dir.join("cache"), &record).unwrap());
    let events = events.into_inner().unwrap();
    let kernel: Vec<_> =
        events.iter().filter_map(|e| if let Event::Kernel(n, d, of) = e { Some((n, *d, *of)) } else { None }).collect();
    let &(name, done, of) = kernel.last().expect("no kernel walk reported");
    assert!(of > 0 && done == of && kernel.len() >= of, "{kernel:?}");
    let prepared = translucent::PreparedScene::new(&scene, &Default::default()).unwrap();
    assert_eq!(name, &prepared.objects[0].name, "the walk names another object");
    let at = |want: &dyn Fn(&Event) -> bool| events.iter().position(want).unwrap_or_else(|| panic!("{events:?}"));
    let image = at(&|e| matches!(e, Event::Step(Step::TruthImage)));
    assert!(at(&|e| matches!(e, Event::Kernel(..))) < image && image < at(&|e| matches!(e, Event::Run(..))));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 49, part 4: `--render-models dipole,transport` sweeps the renderer once per model.
/// Each model's rows are measured against its own exact exitance and all against the one
/// reference: the dipole's rows need no precompute and the transport rows carry their kernel's
/// walk time; the model error is one figure per model, and the two differ; every row's total
/// error keeps within the triangle inequality's bound of its own model and discretisation
/// errors; and light.png and study.md's section rank the configurations against the light.
#[test]
fn study_render_models_sweeps_each_model_against_the_one_reference_with_its_precompute() {
    let dir = temp_dir("study-render-models");
    let (scene, out, cache) = (repo_path("tests/scenes/study-tiny.toml"), dir.join("out"), dir.join("cache"));
    let run = quick_physics_study(&scene, &out, &cache, ["--render-models", "dipole,transport"]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let (w, h) = image::image_dimensions(out.join("light.png")).expect("light.png");
    assert_eq!((w, h), (960, 640));
    let md = std::fs::read_to_string(out.join("study.md")).unwrap();
    assert!(md.contains("## The models against the light") && md.contains("| transport | "), "{md}");
    assert!(text(&run.stdout).contains("against the light <="), "{}", text(&run.stdout));
    let rows = csv_rows(&std::fs::read_to_string(out.join("study.csv")).unwrap());
    let of = |m: &str| rows.iter().filter(|r| r["model"] == m).collect::<Vec<_>>();
    let (dipole, transport) = (of("dipole"), of("transport"));
    assert_eq!(dipole.len(), 7);
    assert_eq!(transport.len(), 7);
    assert!(dipole.iter().all(|r| r["precompute_s"].parse::<f64>().unwrap() == 0.0));
    assert!(transport.iter().all(|r| r["precompute_s"].parse::<f64>().unwrap() > 0.0));
    let model = |r: &Row| channels(r, "model_rel_rms");
    assert!(dipole.iter().all(|&r| model(r) == model(dipole[0])));
    assert!(transport.iter().all(|&r| model(r) == model(transport[0])));
    assert_ne!(model(dipole[0]), model(transport[0]), "the kernel's exact exitance is not the dipole's");
    for r in dipole.iter().chain(&transport).copied() {
        let (m, d, t, n) = (model(r), channels(r, "rel_rms"), channels(r, "total_rel_rms"), channels(r, "rte_noise"));
        for c in 0..3 {
            assert!(t[c].is_finite() && t[c] <= m[c] + d[c] * (1.0 + m[c]) + 3.0 * n[c], "channel {c}: {r:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--physics` with a budget that budgets nothing is refused before any work, naming the flag,
/// with a non-zero exit and no output folder.
#[test]
fn study_physics_refuses_an_empty_budget_naming_the_flag_and_writes_nothing() {
    let dir = temp_dir("study-physics-bad");
    let out = dir.join("out");
    for (flag, value) in [
        ("--rte-stderr", "0"),
        ("--rte-stderr", "nan"),
        ("--rte-photons", "0"),
        ("--rte-seconds", "-1"),
        ("--rte-walk", "sideways"),
        ("--rte-receivers", "0"),
        ("--models", "nonsense"),
        ("--render-models", "nonsense"),
    ] {
        let run = translucent(&["study", "-o", out.to_str().unwrap(), "--physics", flag, value], &[]);
        let err = text(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{flag} {value}: {err}");
        assert!(err.contains(flag) && !err.contains("panicked"), "{flag} {value}: {err}");
        assert!(!out.exists(), "{flag} {value} made the output folder");
    }
}

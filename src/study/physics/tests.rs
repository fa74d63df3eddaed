//! Unit tests of the study's physics report: crossovers, the reference's noise, per band.
use super::*;

fn row(samples: usize, seed: u64, err: [f64; 3]) -> Row {
    Row {
        scene: "s".into(),
        model: String::new(),
        precompute_s: 0.0,
        default: false,
        sampler: "turk".into(),
        samples,
        gather: "vertex".into(),
        epsilon: None,
        seed,
        sampling_ms: 1.0,
        splat_ms: 1.0,
        gather_ms: 1.0,
        shade_ms: 1.0,
        frame_ms: 3.0,
        device_mib: 1.0,
        rel_rms: err,
        p99: err,
        max: err,
        bias: [0.0; 3],
        image_rel_rmse: 0.0,
        flip_mean: 0.0,
        predicted: [f64::NAN; 3],
        model_rel_rms: [0.01; 3],
        total_rel_rms: err,
        rte_noise: [0.001; 3],
    }
}

#[test]
fn the_crossover_is_the_count_from_which_every_larger_count_stays_below_the_model_error() {
    let rows = vec![
        row(100, 1, [0.05, 0.005, 0.05]),
        row(200, 1, [0.02, 0.004, 0.05]),
        // Two seeds at 400: their mean, 0.009 for r, is below the model's 0.01.
        row(400, 1, [0.008, 0.02, 0.05]),
        row(400, 2, [0.010, 0.001, 0.05]),
        row(800, 1, [0.004, 0.001, 0.05]),
    ];
    let x = crossovers(&rows, [0.01; 3]);
    assert_eq!(x.len(), 1);
    assert_eq!(x[0].counts, [100, 200, 400, 800]);
    // g dips below at 100 and 200, rises above at 400 (mean 0.0105), so pays until 800.
    assert_eq!(x[0].from, [Some(400), Some(800), None]);
}

#[test]
fn noise_is_the_rms_relative_standard_error_over_lit_vertices() {
    // The third vertex is under the lit floor in every channel and left out.
    let m = vec![vec![[1.0; 3], [2.0; 3], [1e-9; 3]]];
    let s = vec![vec![[0.03; 3], [0.08; 3], [1.0; 3]]];
    let n = noise(&m, &s);
    let expected = ((0.03f64.powi(2) + 0.04f64.powi(2)) / 2.0).sqrt();
    assert!(n.iter().all(|v| (v - expected).abs() < 1e-15), "{n:?}");
    assert!((without_noise(0.05, 0.03) - 0.04).abs() < 1e-15);
    assert_eq!(without_noise(0.01, 0.03), 0.0);
}

#[test]
fn band_noise_keeps_each_bands_vertices_under_the_objects_own_lit_floor() {
    // Facing, at the terminator and twice on the unlit side, where the dimmer one is under
    // the floor the facing vertex sets: left out, as in `band_errors`.
    let m = vec![vec![[1.0; 3], [0.5; 3], [0.2; 3], [1e-9; 3]]];
    let s = vec![vec![[0.01; 3], [0.02; 3], [0.08; 3], [1.0; 3]]];
    let cosines = vec![vec![0.9, 0.1, -0.5, -0.9]];
    let n = band_noise(&m, &s, &cosines);
    assert_eq!(n.len(), BANDS.len());
    let expected = [0.01, f64::NAN, 0.04, 0.4];
    for (band, e) in n.iter().zip(expected) {
        for v in band {
            assert!(v.is_nan() && e.is_nan() || (v - e).abs() < 1e-15, "{n:?}");
        }
    }
}

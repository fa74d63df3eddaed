//! The hierarchical gather (`render.gather = "hierarchical"`, glsl/gather_tree.comp): the GPU
//! against its f64 twin (`reference::tree`), epsilon = 0 against the flat sum, and the default
//! epsilon against the flat gather on the default scene, on uniformly lit planes and across a
//! shadow edge. All on lavapipe with validation on.

mod common;

use common::{builtin, gather_from, plane_scene, run_all, temp_dir, text, translucent, with_gpu};
use translucent::optics::{Material, fresnel};
use translucent::reference;
use translucent::scene::build::{Overrides, PreparedScene};
use translucent::scene::{DEFAULT_GATHER_EPSILON, GatherMode, Scene, TransportMode};

fn hierarchical(epsilon: f32) -> Overrides {
    Overrides {
        resolution: Some([64, 64]),
        gather: Some(GatherMode::Hierarchical),
        gather_epsilon: Some(epsilon),
        // Every vertex is compared: whole meshes.
        level_of_detail: Some(false),
        ..Default::default()
    }
}

/// Per vertex and channel, |a - b| / b with a floor at 1e-3 of b's peak for the darkest
/// vertices: (worst, RMS over vertices brighter than 1% of the peak).
fn compare(a: &[[f64; 3]], b: &[[f64; 3]]) -> (f64, f64) {
    let peak = b.iter().flat_map(|m| m.iter()).fold(0.0f64, |x, y| x.max(*y));
    let (mut worst, mut sum_sq, mut n) = (0.0f64, 0.0, 0);
    for (x, y) in a.iter().zip(b) {
        for c in 0..3 {
            let e = (x[c] - y[c]).abs() / y[c].max(1e-3 * peak);
            worst = worst.max(e);
            if y[c] > 1e-2 * peak {
                sum_sq += e * e;
                n += 1;
            }
        }
    }
    (worst, (sum_sq / n.max(1) as f64).sqrt())
}

fn widen(v: &[[f32; 3]]) -> Vec<[f64; 3]> {
    v.iter().map(|m| m.map(f64::from)).collect()
}

#[test]
fn hierarchical_gather_matches_its_f64_twin() {
    with_gpu(|gpu| {
        for epsilon in [DEFAULT_GATHER_EPSILON, 1.0] {
            let prepared = builtin(&hierarchical(epsilon));
            let irradiance = reference::splat(&prepared, &reference::occluders(&prepared));
            let expected = reference::tree::gather(&prepared, &irradiance, epsilon as f64);
            let got = widen(&gather_from(gpu, prepared, &irradiance));
            let (worst, rms) = compare(&got, &expected[0]);
            eprintln!("epsilon {epsilon}: GPU vs f64 twin worst {worst:.2e}, RMS {rms:.2e}");
            assert!(worst < 1e-3, "epsilon {epsilon}: worst relative error {worst}");
        }
    });
}

#[test]
fn epsilon_zero_is_the_flat_gather() {
    with_gpu(|gpu| {
        let prepared = builtin(&hierarchical(0.0));
        let irradiance = reference::splat(&prepared, &reference::occluders(&prepared));
        // The f64 twins: the same terms in another order.
        let flat = reference::gather(&prepared, &irradiance);
        let tree = reference::tree::gather(&prepared, &irradiance, 0.0);
        let (worst, _) = compare(&tree[0], &flat[0]);
        assert!(worst < 1e-12, "f64: tree with epsilon 0 vs flat: {worst}");
        // The GPU passes.
        let flat_overrides = Overrides { gather: Some(GatherMode::Vertex), ..hierarchical(0.0) };
        let gpu_flat = widen(&gather_from(gpu, builtin(&flat_overrides), &irradiance));
        let gpu_tree = widen(&gather_from(gpu, prepared, &irradiance));
        let (worst, _) = compare(&gpu_tree, &gpu_flat);
        eprintln!("GPU: hierarchical with epsilon 0 vs the vertex gather: worst {worst:.2e}");
        assert!(worst < 1e-5, "GPU: epsilon 0 vs flat: {worst}");
    });
}

#[test]
fn default_epsilon_is_within_half_a_percent_rms_of_the_flat_gather() {
    with_gpu(|gpu| {
        let prepared = builtin(&hierarchical(DEFAULT_GATHER_EPSILON));
        let irradiance = reference::splat(&prepared, &reference::occluders(&prepared));
        let flat = reference::gather(&prepared, &irradiance);
        let got = widen(&gather_from(gpu, prepared, &irradiance));
        let (worst, rms) = compare(&got, &flat[0]);
        eprintln!(
            "default scene, epsilon {DEFAULT_GATHER_EPSILON}: against the flat gather RMS {:.3}%, worst {:.2}%",
            100.0 * rms,
            100.0 * worst
        );
        assert!(rms < 0.005, "RMS {rms}");
    });
}

/// A 1 m translucent plane (1 unit = 1 mm) lit from straight above, 3,000 Poisson samples,
/// every channel gathered (the samples lie several profile radii apart, where the planner
/// would compute some channels locally and leave the gather nothing to show).
fn plane(preset: &str, gather: GatherMode) -> PreparedScene {
    let scene = Scene::parse(&plane_scene(preset, 1000.0, 3000, ""), "plane", None).unwrap();
    let overrides = Overrides {
        gather: Some(gather),
        transport: Some(TransportMode::Gather),
        level_of_detail: Some(false),
        ..Default::default()
    };
    PreparedScene::new(&scene, &overrides).unwrap()
}

#[test]
fn uniformly_lit_planes_keep_total_reflectance_at_the_default_epsilon() {
    with_gpu(|gpu| {
        for preset in ["marble", "skimmilk", "ketchup", "spectralon"] {
            let material = Material::preset(preset).unwrap();
            let dipoles = material.dipoles(1.0).unwrap();
            let f_t = fresnel::fresnel_transmittance(1.0, material.eta);
            let mean = |gather| {
                let prepared = plane(preset, gather);
                let mesh = prepared.objects[0].mesh.clone();
                let exitance = common::run_all(gpu, prepared).exitance(0).unwrap();
                // Vertices within 100 mm of the centre see the plane as infinite.
                let middle: Vec<usize> =
                    (0..mesh.positions().len()).filter(|&v| mesh.positions()[v].length() < 100.0).collect();
                [0, 1, 2].map(|c| middle.iter().map(|&v| exitance[v][c] as f64).sum::<f64>() / middle.len() as f64)
            };
            let (tree, flat) = (mean(GatherMode::Hierarchical), mean(GatherMode::Vertex));
            for c in 0..3 {
                let expected = dipoles[c].r_d_total() * f_t;
                let (e_tree, e_flat) = ((tree[c] - expected) / expected, (flat[c] - expected) / expected);
                eprintln!("{preset} channel {c}: hierarchical {e_tree:+.2e}, flat {e_flat:+.2e} from R_d,total F_t");
                // The hierarchy adds at most 1e-3 to what the flat sum makes of this sample set.
                assert!((tree[c] - flat[c]).abs() < 1e-3 * expected, "{preset} channel {c}: {tree:?} vs {flat:?}");
                assert!(e_tree.abs() < 0.02, "{preset} channel {c}: {e_tree}");
            }
        }
    });
}

#[test]
fn a_bad_gather_epsilon_is_an_error_naming_it() {
    let dir = temp_dir("epsilon");
    let png = dir.join("out.png");
    let out = translucent(
        &["render", "--gather", "hierarchical", "--gather-epsilon", "-1", "-o", png.to_str().unwrap()],
        &[],
    );
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("--gather-epsilon -1 must be 0 to 10"), "{}", text(&out.stderr));
    let scene = dir.join("bad.toml");
    let toml =
        plane_scene("marble", 1000.0, 3000, "").replace("[sampling]", "[render]\ngather_epsilon = 11.0\n\n[sampling]");
    std::fs::write(&scene, toml).unwrap();
    let out = translucent(&["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap()], &[]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("render.gather_epsilon") && stderr.contains("must be 0 to 10") && stderr.contains("line 18"),
        "{stderr}"
    );
    assert!(!png.exists());

    // Epsilon 0 lists every sample for every group of vertices: a scene where that exceeds the
    // device's storage-buffer range is refused before any GPU work, naming the setting.
    let big = plane_scene("marble", 1000.0, 3000, "")
        .replace("divisions = 48", "divisions = 400")
        .replace("method = \"poisson\"", "method = \"random\"")
        .replace("count = 3000", "count = 8000")
        .replace("[sampling]", "[render]\ngather = \"hierarchical\"\ngather_epsilon = 0.0\n\n[sampling]");
    std::fs::write(&scene, big).unwrap();
    let out = translucent(&["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap()], &[]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("render.gather_epsilon 0") && stderr.contains("maxStorageBufferRange"), "{stderr}");
    assert!(!png.exists());
}

#[test]
fn a_coarse_level_of_detail_gathers_hierarchically_at_its_own_vertices_as_the_whole_mesh_does() {
    // At 64x64 the bunny is drawn at a coarse level: the gather runs at that level's vertices,
    // grouped and cut anew, and must agree there with the whole mesh's gather within the
    // epsilon's own error.
    let epsilon = translucent::scene::ACCURATE_GATHER_EPSILON;
    let lod = Overrides { level_of_detail: Some(true), ..hierarchical(epsilon) };
    let (level, vertices, coarse, whole) = with_gpu(|gpu| {
        let at = run_all(gpu, builtin(&lod)).exitance_at_level(0).unwrap();
        let (level, vertices, coarse) = (at.level, at.vertices, at.values);
        let whole = run_all(gpu, builtin(&hierarchical(epsilon))).exitance(0).unwrap();
        (level, vertices, coarse, whole)
    });
    assert!(level > 0, "the 64x64 view draws the bunny coarse");
    let at: Vec<[f64; 3]> = vertices.iter().map(|&v| whole[v as usize].map(f64::from)).collect();
    let got: Vec<[f64; 3]> = coarse.iter().map(|m| m.map(f64::from)).collect();
    let (worst, rms) = compare(&got, &at);
    eprintln!("level {level}, {} vertices: worst {worst:.4}, RMS {rms:.5} against the whole mesh", vertices.len());
    // Measured at level 6 (591 vertices): RMS 0.54%, and three vertices 6 to 9% off (12 to 15%
    // of the peak); their cause is not found yet (docs/STUDY.md).
    assert!(rms < 1e-2 && worst < 0.15, "level {level}: worst {worst}, RMS {rms}");
}

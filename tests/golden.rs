//! Golden images on lavapipe: the built-in scene at 256x256, and the glTF scene
//! `assets/scenes/bunny-volume.glb` at 128x128 and 2,000 samples.
//!
//! Regenerate (only after a deliberate change to the picture, and look at it first):
//!     TRANSLUCENT_BLESS=1 cargo test --test golden
//! which rewrites tests/golden/*.png and says so. A missing golden is a failure.

mod common;

use common::{repo_path, run_all, with_gpu};
use translucent::scene::build::Overrides;

#[test]
fn default_scene_matches_the_golden_image() {
    // At its own defaults (the 1% error target), not the tests' 400 samples.
    let overrides = Overrides { resolution: Some([256, 256]), ..Default::default() };
    matches_golden(&translucent::Scene::builtin(), &overrides, "default-256.png", 256);
}

#[cfg(feature = "gltf")]
#[test]
fn the_gltf_scene_matches_its_golden_image() {
    let scene = translucent::Scene::load(&repo_path("assets/scenes/bunny-volume.glb")).unwrap();
    let overrides = Overrides { resolution: Some([128, 128]), samples: Some(2000), ..Default::default() };
    matches_golden(&scene, &overrides, "bunny-volume-128.png", 128);
}

/// `scene` rendered square at `size` pixels with `overrides` is within a mean absolute
/// difference of 1/255 of `tests/golden/NAME` (written instead under `TRANSLUCENT_BLESS=1`).
fn matches_golden(scene: &translucent::Scene, overrides: &Overrides, name: &str, size: u32) {
    let golden = repo_path(&format!("tests/golden/{name}"));
    let (rgba, non_finite) = with_gpu(|gpu| {
        let prepared = translucent::PreparedScene::new(scene, overrides).unwrap();
        run_all(gpu, prepared).image().unwrap()
    });
    assert_eq!(non_finite, 0, "{non_finite} NaN or infinite pixels before tone mapping");
    if std::env::var("TRANSLUCENT_BLESS").is_ok_and(|v| v == "1") {
        translucent::output::write_png(&golden, size, size, &rgba).unwrap();
        eprintln!("TRANSLUCENT_BLESS=1: wrote a new golden image {}", golden.display());
        return;
    }
    let expected = image::open(&golden)
        .unwrap_or_else(|e| {
            panic!(
                "no golden image at {} ({e}); create it with TRANSLUCENT_BLESS=1 cargo test --test golden",
                golden.display()
            )
        })
        .to_rgba8();
    assert_eq!(expected.dimensions(), (size, size));
    let total: u64 = expected.as_raw().iter().zip(&rgba).map(|(a, b)| a.abs_diff(*b) as u64).sum();
    let mean = total as f64 / rgba.len() as f64;
    let differing = expected.as_raw().chunks(4).zip(rgba.chunks(4)).filter(|(a, b)| a != b).count();
    let flip = translucent::study::flip::flip_mean(expected.as_raw(), &rgba, size, size).unwrap();
    eprintln!(
        "golden {name}: mean absolute difference {mean:.4} (of 255), {differing} pixels differ, FLIP mean {flip:.4}"
    );
    assert!(mean < 1.0, "mean absolute difference {mean:.3}/255 from {}", golden.display());
}

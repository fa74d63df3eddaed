//! Golden image of the built-in scene at 256x256 on lavapipe.
//!
//! Regenerate (only after a deliberate change to the picture, and look at it first):
//!     TRANSLUCENT_BLESS=1 cargo test --test golden
//! which rewrites tests/golden/default-256.png and says so. A missing golden is a failure.

mod common;

use common::{repo_path, run_all, with_gpu};
use translucent::scene::build::Overrides;

#[test]
fn default_scene_matches_the_golden_image() {
    let golden = repo_path("tests/golden/default-256.png");
    let (rgba, non_finite) = with_gpu(|gpu| {
        let overrides = Overrides { resolution: Some([256, 256]), ..Default::default() };
        // At its own defaults (the 1% error target), not the tests' 400 samples.
        let prepared = translucent::PreparedScene::new(&translucent::Scene::builtin(), &overrides).unwrap();
        run_all(gpu, prepared).image().unwrap()
    });
    assert_eq!(non_finite, 0, "{non_finite} NaN or infinite pixels before tone mapping");
    if std::env::var("TRANSLUCENT_BLESS").is_ok_and(|v| v == "1") {
        translucent::output::write_png(&golden, 256, 256, &rgba).unwrap();
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
    assert_eq!(expected.dimensions(), (256, 256));
    let total: u64 = expected.as_raw().iter().zip(&rgba).map(|(a, b)| a.abs_diff(*b) as u64).sum();
    let mean = total as f64 / rgba.len() as f64;
    let differing = expected.as_raw().chunks(4).zip(rgba.chunks(4)).filter(|(a, b)| a != b).count();
    let flip = translucent::study::flip::flip_mean(expected.as_raw(), &rgba, 256, 256).unwrap();
    eprintln!("golden: mean absolute difference {mean:.4} (of 255), {differing} pixels differ, FLIP mean {flip:.4}");
    assert!(mean < 1.0, "mean absolute difference {mean:.3}/255 from {}", golden.display());
}

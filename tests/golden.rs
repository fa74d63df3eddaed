//! Golden image of the built-in scene at 256x256 on lavapipe.
//!
//! Regenerate (only after a deliberate change to the picture, and look at it first):
//!     TRANSLUCENT_BLESS=1 cargo test --test golden
//! which rewrites tests/golden/default-256.png and says so. A missing golden is a failure.

mod common;

use common::with_gpu;
use std::path::PathBuf;
use translucent::render::plan::Change;
use translucent::render::renderer::Renderer;
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

#[test]
fn default_scene_matches_the_golden_image() {
    let golden = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden/default-256.png");
    let (rgba, non_finite) = with_gpu(|gpu| {
        let overrides = Overrides { resolution: Some([256, 256]), ..Default::default() };
        let prepared = PreparedScene::new(&Scene::builtin(), &overrides).unwrap();
        let mut renderer = Renderer::new(gpu, prepared).unwrap();
        let plan = renderer.plan(Change::Everything);
        renderer.frame(&plan).unwrap();
        renderer.image().unwrap()
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
    eprintln!("golden: mean absolute difference {mean:.4} (of 255), {differing} pixels differ");
    assert!(mean < 1.0, "mean absolute difference {mean:.3}/255 from {}", golden.display());
}

//! How frame time grows with the work: resolution, triangles, translucent objects and lights,
//! each swept alone on a small scene, with the fitted exponent (least-squares slope of log time
//! on log work). Frames are timed by timestamps (the sum of the passes, median of several after
//! a warm-up), camera-only and key-light-moving, so the two kinds of growth show apart.

use std::sync::Arc;
use translucent::gpu::{Gpu, median};
use translucent::render::plan::Change;
use translucent::render::renderer::Renderer;
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

const FRAMES: usize = 5;

/// A marble sphere scene: `spheres` 2 cm spheres of `divisions` on a grid, `lights` directional
/// lights spread over the upper hemisphere, no shadows (so the light sweep measures shading and
/// splat, not shadow maps), drawn at `resolution`^2.
pub fn sphere_scene(spheres: usize, divisions: u32, lights: usize, resolution: u32) -> String {
    let side = (spheres as f64).sqrt().ceil() as usize;
    let extent = 0.03 * side as f64;
    let mut toml = format!(
        "[camera]\neye = [0.0, {:.4}, {:.4}]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 30.0\nresolution = [{resolution}, {resolution}]\n\
         [render]\nlevel_of_detail = false\n",
        0.4 * extent + 0.01,
        1.6 * extent + 0.04
    );
    for i in 0..spheres {
        let (x, z) = (
            (i % side) as f64 * 0.03 - 0.015 * (side - 1) as f64,
            (i / side) as f64 * 0.03 - 0.015 * (side - 1) as f64,
        );
        toml += &format!(
            "[[object]]\nshape = {{ type = \"sphere\", radius = 0.01, divisions = {divisions} }}\n\
             material = {{ type = \"translucent\", preset = \"marble\", mm_per_unit = 1000.0 }}\n\
             casts_shadow = false\ntransform = {{ translate = [{x:.4}, 0.0, {z:.4}] }}\n"
        );
    }
    for l in 0..lights {
        // A golden-angle spiral over the upper hemisphere.
        let y = 1.0 - (l as f64 + 0.5) / lights as f64 * 0.9;
        let phi = l as f64 * 2.399_963;
        let r = (1.0 - y * y).sqrt();
        toml += &format!(
            "[[light]]\ntype = \"directional\"\ndirection = [{:.4}, {y:.4}, {:.4}]\nirradiance = [{e:.4}, {e:.4}, {e:.4}]\nshadows = false\n",
            r * phi.cos(),
            r * phi.sin(),
            e = 1.0 / lights as f64
        );
    }
    toml
}

/// Median timestamp totals (ms) of camera-only and light-moving frames of `renderer`.
fn frame_times(renderer: &mut Renderer) -> (f64, f64) {
    let mut out = [0.0; 2];
    for (k, change) in [Change::Camera, Change::Light(0)].into_iter().enumerate() {
        let mut times = Vec::new();
        for frame in 0..1 + FRAMES {
            super::step(renderer, change);
            let plan = renderer.plan(change);
            let total = renderer.frame(&plan).expect("frame").total();
            if frame > 0 {
                times.push(total);
            }
        }
        out[k] = median(&mut times);
    }
    (out[0], out[1])
}

fn renderer_for(gpu: &Arc<Gpu>, scene: &Scene, overrides: &Overrides) -> Renderer {
    let prepared = PreparedScene::new(scene, overrides).expect("growth scene");
    let mut renderer = Renderer::new(gpu, prepared).expect("renderer");
    renderer.frame(&renderer.plan(Change::Everything)).expect("first frame");
    renderer
}

/// One sweep: a row per (work, scene), then the fitted exponents.
fn sweep(gpu: &Arc<Gpu>, title: &str, unit: &str, rows: Vec<(f64, Scene, Overrides)>) {
    println!("\n{title}:");
    println!("  {unit:>12} {:>12} {:>12}", "camera ms", "light ms");
    let (mut x, mut camera, mut light) = (Vec::new(), Vec::new(), Vec::new());
    for (work, scene, overrides) in rows {
        let (c, l) = frame_times(&mut renderer_for(gpu, &scene, &overrides));
        println!("  {work:>12.0} {c:>12.2} {l:>12.2}");
        x.push(work.ln());
        camera.push(c.ln());
        light.push(l.ln());
    }
    println!(
        "  fitted exponent (time ~ work^k): camera k = {:.2}, light k = {:.2}",
        super::slope(&x, &camera),
        super::slope(&x, &light)
    );
}

fn parsed(toml: &str, name: &str) -> Scene {
    Scene::parse(toml, name, None).expect("growth scene parses")
}

/// The four sweeps.
pub fn growth(gpu: &Arc<Gpu>) {
    println!("\nGrowth with the work (timestamps: sum of the passes, median of {FRAMES} frames after one):");
    let resolution = [256u32, 512, 1024, 2048]
        .map(|r| ((r * r) as f64, Scene::builtin(), Overrides { resolution: Some([r, r]), ..Default::default() }));
    sweep(gpu, "built-in scene against pixels (256^2 to 2048^2)", "pixels", resolution.into());
    let triangles = [32u32, 64, 128, 256, 512].map(|d| {
        let t = 4 * d as usize * d as usize - 4 * d as usize;
        (t as f64, parsed(&sphere_scene(1, d, 1, 512), "sphere"), Overrides::default())
    });
    sweep(
        gpu,
        "one marble sphere against triangles, every triangle drawn (level of detail off)",
        "triangles",
        triangles.into(),
    );
    let objects =
        [1usize, 4, 16, 64].map(|n| (n as f64, parsed(&sphere_scene(n, 24, 1, 512), "spheres"), Overrides::default()));
    sweep(gpu, "marble spheres (24 divisions each) against their count", "objects", objects.into());
    let lights =
        [1usize, 4, 16, 64].map(|n| (n as f64, parsed(&sphere_scene(1, 24, n, 512), "lights"), Overrides::default()));
    sweep(gpu, "one marble sphere against directional lights (no shadows)", "lights", lights.into());
}

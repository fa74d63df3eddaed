//! The "models" section: what single scattering between points (`material.model = "auto"`)
//! costs beside the dipole on the accuracy study's 2 cm ketchup sphere, light-moving frames,
//! the renderers stepped side by side (alternating, so outside load falls on all alike). Each
//! row is printed as its median gather and frame by timestamps and its frame's ratio to the
//! dipole's; issue 26 asks at most 1.5x at the default opening.

use super::{FRAMES, WARM_UP, step};
use std::sync::Arc;
use translucent::gpu::{Gpu, median};
use translucent::render::plan::{Change, Pass};
use translucent::render::renderer::Renderer;
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

/// Light-moving frames per renderer after the warm-up: more than `FRAMES`, since a frame here
/// is short and five rows alternate.
const MODEL_FRAMES: usize = 3 * FRAMES;

/// The study's ketchup sphere with `model`, `render.beam_opening` and `render.beam_walk_mib`.
fn ketchup(gpu: &Arc<Gpu>, model: &str, opening: f32, walk_mib: u32) -> Renderer {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/sphere-ketchup.toml");
    let text = std::fs::read_to_string(path).expect("assets/scenes/sphere-ketchup.toml");
    let text = text.replace("mm_per_unit = 1000.0", &format!("mm_per_unit = 1000.0, model = \"{model}\""));
    let scene =
        Scene::parse(&text, path, Some(std::path::PathBuf::from(path).parent().unwrap().into())).expect("scene");
    let mut prepared = PreparedScene::new(&scene, &Overrides::default()).expect("prepared");
    prepared.scene.file.render.beam_opening = opening;
    prepared.scene.file.render.beam_walk_mib = walk_mib;
    let mut renderer = Renderer::new(gpu, prepared).expect("renderer");
    renderer.frame(&renderer.plan(Change::Everything)).expect("first frame");
    renderer
}

pub fn models(gpu: &Arc<Gpu>) {
    let default = translucent::scene::DEFAULT_BEAM_OPENING;
    let walks = translucent::scene::DEFAULT_BEAM_WALK_MIB;
    let rows = [
        ("dipole", ketchup(gpu, "dipole", default, walks)),
        ("auto, opening 0", ketchup(gpu, "auto", 0.0, walks)),
        ("auto, opening 0.2 (default)", ketchup(gpu, "auto", default, walks)),
        ("auto, 0.2, walked each frame", ketchup(gpu, "auto", default, 0)),
        ("auto, opening 0.3", ketchup(gpu, "auto", 0.3, walks)),
    ];
    let (names, mut renderers): (Vec<_>, Vec<_>) = rows.into_iter().unzip();
    let (mut gather, mut frame) = (vec![Vec::new(); names.len()], vec![Vec::new(); names.len()]);
    for f in 0..WARM_UP + MODEL_FRAMES {
        for (i, renderer) in renderers.iter_mut().enumerate() {
            step(renderer, Change::Light(0));
            let timings = renderer.frame(&renderer.plan(Change::Light(0))).expect("frame");
            if f >= WARM_UP {
                gather[i].push(timings.get(Pass::Gather).unwrap_or(f64::NAN));
                frame[i].push(timings.passes.iter().map(|(_, ms)| ms).sum::<f64>());
            }
        }
    }
    let frame: Vec<f64> = frame.iter_mut().map(|v| median(v)).collect();
    println!(
        "\nmodels: the 2 cm ketchup sphere, light-moving frames, timestamps, medians of {MODEL_FRAMES} side by side"
    );
    println!("  {:<30} {:>10} {:>10} {:>10}", "renderer", "gather ms", "frame ms", "vs dipole");
    for (i, name) in names.iter().enumerate() {
        let g = median(&mut gather[i]);
        println!("  {name:<30} {g:>10.2} {:>10.2} {:>9.2}x", frame[i], frame[i] / frame[0]);
    }
}

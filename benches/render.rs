//! Renderer benchmark: per-pass GPU times and frames per second on the default scene, and the
//! seed paper's FPS-against-sample-count comparison (its Figure 7), on whatever device the
//! loader offers (TRANSLUCENT_DEVICE to choose). Prints figures; asserts nothing.
//!
//!     cargo bench --bench render [-- frames|savings|levels|terms|hierarchy|growth|models|transport|receivers|
//!                                    planner|gathers]
//!
//! Two timings per pass: GPU timestamp queries inside one submission, and the wall time of the
//! pass submitted alone (submission to fence). On lavapipe a timestamp used to be taken only at
//! the rasteriser's next flush, after any compute dispatch recorded behind it; `GpuTimer` now
//! records a barrier after each start stamp, which flushes there, and the two figures agree.
//! Frames per second come from whole-frame wall time.

#[path = "render/growth.rs"]
mod growth;
#[path = "render/models.rs"]
mod models;
#[path = "render/receivers.rs"]
mod receivers;
#[path = "render/roofline.rs"]
mod roofline;

use roofline::{Roofline, Yardsticks};
use std::sync::Arc;
use std::time::Instant;
use translucent::SceneEdit;
use translucent::gpu::{Gpu, GpuOptions, median};
use translucent::render::plan::{Change, Pass};
use translucent::render::renderer::Renderer;
use translucent::sampling::Method;
use translucent::scene::build::{Overrides, PreparedScene};
use translucent::scene::{DEFAULT_GATHER_EPSILON, GatherMode};
use translucent::scene::{Scene, lights};

const WARM_UP: usize = 1;
const FRAMES: usize = 5;
/// Gather-only timings take more frames: they are cheap, and on a shared machine a median of 9
/// shrugs off more bursts of outside load than one of 5.
const GATHER_FRAMES: usize = 9;

struct Measured {
    /// (pass, median timestamp ms, median isolated wall ms)
    passes: Vec<(String, f64, f64)>,
    frame_wall_ms: f64,
}

fn measure(renderer: &mut Renderer, change: Change) -> Measured {
    let mut stamp: Vec<(String, Vec<f64>)> = Vec::new();
    let mut isolated: Vec<(String, Vec<f64>)> = Vec::new();
    let mut walls = Vec::new();
    let step = |renderer: &mut Renderer| {
        if let Change::Light(i) = change {
            let scene = renderer.scene();
            let moved = lights::orbit(&scene.scene.file.lights[i], scene.bounds.0, 3.0).expect("a key light");
            renderer.edit(SceneEdit::Light { index: i, light: moved }).expect("orbit");
        }
        renderer.plan(change)
    };
    for frame in 0..WARM_UP + FRAMES {
        let plan = step(renderer);
        let start = Instant::now();
        let timings = renderer.frame(&plan).expect("frame");
        let wall = start.elapsed().as_secs_f64() * 1e3;
        let plan = step(renderer);
        let alone = renderer.frame_isolated(&plan).expect("isolated frame");
        if frame < WARM_UP {
            continue;
        }
        walls.push(wall);
        for (into, from) in [(&mut stamp, timings.passes), (&mut isolated, alone.passes)] {
            for (pass, ms) in from {
                let name = pass.name().to_string();
                match into.iter_mut().find(|(n, _)| *n == name) {
                    Some((_, v)) => v.push(ms),
                    None => into.push((name, vec![ms])),
                }
            }
        }
    }
    let passes = stamp
        .into_iter()
        .map(|(name, mut v)| {
            let mut alone = isolated.iter().find(|(n, _)| *n == name).map(|(_, v)| v.clone()).unwrap_or_default();
            let m = median(&mut alone);
            (name, median(&mut v), m)
        })
        .collect();
    Measured { passes, frame_wall_ms: median(&mut walls) }
}

fn print(title: &str, m: &Measured) {
    println!("\n{title}");
    println!("  {:<8} {:>14} {:>16}", "pass", "timestamps ms", "alone (wall) ms");
    for (name, stamp, alone) in &m.passes {
        println!("  {name:<8} {stamp:>14.2} {alone:>16.2}");
    }
    println!("  frame wall time {:.1} ms = {:.2} frames/s", m.frame_wall_ms, 1000.0 / m.frame_wall_ms);
}

/// Median isolated wall time (submission to fence) of the renderer's gather alone, and of
/// glsl/bench/gather_naive.comp over the same vertex-sample pairs, alternating the two
/// `FRAMES` times after a warm-up: (gather ms, naive ms, pairs).
fn gather_against_naive(gpu: &Arc<Gpu>, renderer: &mut Renderer) -> (f64, f64, f64) {
    let (naive, set, _out) = roofline::naive_gather(gpu, renderer);
    let b = renderer.scene_data();
    let receivers = b.receivers.clone();
    let pairs: f64 = receivers.iter().map(|r| r.vertex_count as f64 * r.sample_count as f64).sum();
    let mut plan = renderer.plan(Change::Everything);
    plan.passes.retain(|(p, _)| *p == Pass::Gather);
    // The naive kernel visits every vertex: so does ours here, whatever level the view picks.
    plan.objects.iter_mut().for_each(|o| o.level = 0);
    let (mut ours, mut theirs) = (Vec::new(), Vec::new());
    for frame in 0..WARM_UP + FRAMES {
        let alone = renderer.frame_isolated(&plan).expect("gather");
        let start = Instant::now();
        gpu.one_shot("naive gather", |cmd| {
            for r in &receivers {
                naive.dispatch(cmd, &set, &r.object, [r.vertex_count, 1, 1]);
            }
        })
        .expect("naive gather");
        let naive_ms = start.elapsed().as_secs_f64() * 1e3;
        if frame >= WARM_UP {
            ours.push(alone.passes[0].1);
            theirs.push(naive_ms);
        }
    }
    (median(&mut ours), median(&mut theirs), pairs)
}

/// Median isolated wall time of the gather alone on the current splat (`GATHER_FRAMES` after a
/// warm-up; stage 0 of the hierarchical gather included).
fn gather_alone_ms(renderer: &mut Renderer) -> f64 {
    let mut plan = renderer.plan(Change::Everything);
    plan.passes.retain(|(p, _)| *p == Pass::Gather);
    let mut times: Vec<f64> = (0..WARM_UP + GATHER_FRAMES)
        .map(|_| renderer.frame_isolated(&plan).expect("gather").passes[0].1)
        .skip(WARM_UP)
        .collect();
    median(&mut times)
}

/// The default scene at 512x512 with `overrides` and every mesh whole, after a first frame:
/// for per-vertex comparisons.
fn prepared_renderer(gpu: &Arc<Gpu>, overrides: Overrides) -> Renderer {
    // Per-vertex comparisons need every vertex gathered.
    default_renderer(gpu, Overrides { level_of_detail: Some(false), ..overrides })
}

fn first_exitance(renderer: &Renderer) -> Vec<[f32; 3]> {
    let object = renderer.scene_data().receivers[0].object as usize;
    renderer.exitance(object).expect("exitance")
}

/// Relative RMS of `a` against `b` per vertex and channel, over the vertices brighter than 1%
/// of `b`'s peak (the measure of tests/hierarchy.rs).
fn rms_relative(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let peak = b.iter().flat_map(|m| m.iter()).fold(0.0f32, |x, y| x.max(*y)) as f64;
    let (mut sum_sq, mut n) = (0.0, 0);
    for (x, y) in a.iter().zip(b) {
        for c in 0..3 {
            if y[c] as f64 > 1e-2 * peak {
                let e = (x[c] as f64 - y[c] as f64) / y[c] as f64;
                sum_sq += e * e;
                n += 1;
            }
        }
    }
    (sum_sq / n.max(1) as f64).sqrt()
}

/// The hierarchical gather against the flat vertex gather: an epsilon sweep at 400 and 6,400
/// samples (time and RMS from the flat exitance), then its growth with the sample count.
fn hierarchy(gpu: &Arc<Gpu>) {
    let epsilons = [0.1f32, 0.25, 0.5, 1.0, 2.0, 4.0];
    println!(
        "\nHierarchical gather against the flat vertex gather (default scene, 512x512, gather alone in \
         isolated submissions, median of {GATHER_FRAMES}):"
    );
    println!("  {:>8} {:>8} {:>11} {:>9} {:>14}", "samples", "epsilon", "gather ms", "speed-up", "RMS from flat");
    for count in [400, 6400] {
        let flat_overrides = Overrides { samples: Some(count), ..Default::default() };
        let mut flat = prepared_renderer(gpu, flat_overrides.clone());
        let flat_ms = gather_alone_ms(&mut flat);
        let reference = first_exitance(&flat);
        drop(flat);
        println!("  {count:>8} {:>8} {flat_ms:>11.1} {:>9} {:>14}", "flat", "1.00", "0");
        for &epsilon in &epsilons {
            let overrides = Overrides {
                gather: Some(GatherMode::Hierarchical),
                gather_epsilon: Some(epsilon),
                ..flat_overrides.clone()
            };
            let mut tree = prepared_renderer(gpu, overrides);
            let ms = gather_alone_ms(&mut tree);
            let rms = rms_relative(&first_exitance(&tree), &reference);
            println!("  {count:>8} {epsilon:>8} {ms:>11.1} {:>9.1} {:>13.3}%", flat_ms / ms, 100.0 * rms);
        }
    }
    println!("\nGather time against sample count (default epsilon {DEFAULT_GATHER_EPSILON}; flat up to 1,600):");
    println!("  {:>8} {:>16} {:>12}", "samples", "hierarchical ms", "flat ms");
    let (mut xs, mut ys, mut flat_xs, mut flat_ys) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for count in [400, 800, 1600, 3200, 6400, 12800, 25600] {
        let overrides =
            Overrides { samples: Some(count), gather: Some(GatherMode::Hierarchical), ..Default::default() };
        let ms = gather_alone_ms(&mut prepared_renderer(gpu, overrides));
        let flat = (count <= 1600).then(|| {
            gather_alone_ms(&mut prepared_renderer(gpu, Overrides { samples: Some(count), ..Default::default() }))
        });
        println!("  {count:>8} {ms:>16.1} {:>12}", flat.map(|f| format!("{f:.1}")).unwrap_or_default());
        xs.push((count as f64).ln());
        ys.push(ms.ln());
        if let Some(f) = flat {
            flat_xs.push((count as f64).ln());
            flat_ys.push(f.ln());
        }
    }
    println!(
        "  growth exponent (least-squares slope of log time on log samples): hierarchical {:.2}, flat {:.2}",
        slope(&xs, &ys),
        slope(&flat_xs, &flat_ys)
    );
}

fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let cov: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let var: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    cov / var
}

/// One orbit step of what `change` moves: the key light or the camera, 3 degrees.
fn step(renderer: &mut Renderer, change: Change) {
    match change {
        Change::Light(i) => {
            let scene = renderer.scene();
            let moved = lights::orbit(&scene.scene.file.lights[i], scene.bounds.0, 3.0).expect("a key light");
            renderer.edit(SceneEdit::Light { index: i, light: moved }).expect("orbit");
        }
        _ => renderer.edit(SceneEdit::Camera(renderer.camera().orbited(renderer.scene().bounds.0, 3.0))).expect("camera"),
    }
}

/// What a benchmark renderer does instead of the planner's choice.
#[derive(Clone, Copy, Default)]
struct Force {
    /// Every object at this level of detail (or its coarsest).
    level: Option<usize>,
    /// The shadow filter: one tap (true) or the four-tap tent (false).
    one_tap: Option<bool>,
    /// Opaque objects drawn whole (their levels baked from sky light unused).
    whole_opaque: bool,
    /// Shading terms left out (`Plan::skip_terms`).
    skip_terms: u32,
    /// Every face drawn, the hidden ones too (`Plan::cull_hidden_faces` off).
    every_face: bool,
}

/// Renderers on the default scene at 512x512, one per configuration, stepped side by side
/// through the same frames (alternating, so outside load falls on all alike), each with its
/// `Force`. Returns each one's median frame wall time (ms) and its last image (RGBA8).
fn side_by_side(renderers: &mut [(Renderer, Force)], change: Change, frames: usize) -> Vec<(f64, Vec<u8>, f64)> {
    let mut times = vec![Vec::new(); renderers.len()];
    let mut shade = vec![Vec::new(); renderers.len()];
    for frame in 0..WARM_UP + frames {
        for (((renderer, force), t), shade) in renderers.iter_mut().zip(&mut times).zip(&mut shade) {
            step(renderer, change);
            let mut plan = renderer.plan(change);
            if let Some(level) = force.level {
                for o in &mut plan.objects {
                    o.level = level.min(renderer.needs().objects[o.object].levels.len() - 1);
                }
            }
            if let Some(one_tap) = force.one_tap {
                plan.one_tap_shadows = one_tap;
            }
            plan.skip_terms = force.skip_terms;
            plan.cull_hidden_faces &= !force.every_face;
            if force.whole_opaque {
                plan.objects.iter_mut().filter(|o| o.channels.is_empty()).for_each(|o| o.level = 0);
            }
            let start = Instant::now();
            let timings = renderer.frame(&plan).expect("frame");
            if frame >= WARM_UP {
                t.push(start.elapsed().as_secs_f64() * 1e3);
                shade.push(timings.get(Pass::Shade).unwrap_or(f64::NAN));
            }
        }
    }
    let image = |r: &Renderer| r.image().expect("image").0;
    let rows = renderers.iter().zip(&mut times).zip(&mut shade);
    rows.map(|(((r, _), t), shade)| (median(t), image(r), median(shade))).collect()
}

/// The default scene at 512x512 with `overrides`, after a first frame of everything.
fn default_renderer(gpu: &Arc<Gpu>, overrides: Overrides) -> Renderer {
    let overrides = Overrides { resolution: Some([512, 512]), ..overrides };
    let prepared = PreparedScene::new(&Scene::builtin(), &overrides).expect("default scene");
    let mut renderer = Renderer::new(gpu, prepared).expect("renderer");
    renderer.frame(&renderer.plan(Change::Everything)).expect("first frame");
    renderer
}

fn flip(reference: &[u8], test: &[u8]) -> f64 {
    translucent::study::flip::flip_mean(reference, test, 512, 512).expect("flip")
}

/// What each saving buys: frames per second with every saving on, then with each switched off
/// in turn, light moving and camera moving, and the FLIP mean of each image against the
/// full-detail render of the same frame.
fn savings(gpu: &Arc<Gpu>) {
    let full_detail = Overrides { level_of_detail: Some(false), ..Default::default() };
    let configs: Vec<(&str, Overrides, Force)> = vec![
        ("every saving on (the default)", Overrides::default(), Force::default()),
        ("level of detail off", full_detail.clone(), Force::default()),
        ("floor whole (sky light unbaked)", Overrides::default(), Force { whole_opaque: true, ..Force::default() }),
        ("four-tap shadow filter", Overrides::default(), Force { one_tap: Some(false), ..Force::default() }),
        ("hidden faces drawn", Overrides::default(), Force { every_face: true, ..Force::default() }),
        (
            "full detail, four taps, all faces",
            full_detail,
            Force { one_tap: Some(false), every_face: true, ..Force::default() },
        ),
    ];
    let mut renderers: Vec<(Renderer, Force)> =
        configs.iter().map(|(_, o, f)| (default_renderer(gpu, o.clone()), *f)).collect();
    println!(
        "\nWhat each saving buys, default scene 512x512, {} samples, whole-frame wall time (median of {FRAMES} after \
         {WARM_UP} warm-up), renderers side by side; FLIP mean against the full-detail frame:",
        renderers[0].0.scene().sample_count()
    );
    println!(
        "  {:<32} {:>14} {:>10} {:>15} {:>10} {:>10}",
        "", "light ms", "frames/s", "camera ms", "frames/s", "FLIP"
    );
    let light = side_by_side(&mut renderers, Change::Light(0), FRAMES);
    let camera = side_by_side(&mut renderers, Change::Camera, FRAMES);
    // Every saving off: the reference image.
    let full = configs.len() - 1;
    for (i, (name, _, _)) in configs.iter().enumerate() {
        let (l, c) = (&light[i], &camera[i]);
        println!(
            "  {name:<32} {:>14.1} {:>10.2} {:>15.1} {:>10.2} {:>10.4}",
            l.0,
            1e3 / l.0,
            c.0,
            1e3 / c.0,
            flip(&camera[full].1, &c.1)
        );
    }
    println!("device memory in use (all renderers): {:.1} MiB", gpu.memory_usage().0 as f64 / (1 << 20) as f64);
}

/// Each level of detail of the default scene's bunny forced in turn: triangles, receivers,
/// frame times and the FLIP mean against level 0 (the whole mesh), with the planner's choice.
fn levels(gpu: &Arc<Gpu>) {
    let probe = default_renderer(gpu, Overrides::default());
    let facts = probe.needs().objects.clone();
    let chosen: Vec<usize> = probe.plan(Change::Camera).objects.iter().map(|o| o.level).collect();
    drop(probe);
    let count = facts.iter().map(|f| f.levels.len()).max().unwrap_or(1);
    println!(
        "\nLevels of detail forced in turn, default scene 512x512 (planner's choice: levels {chosen:?}), side by side:"
    );
    println!(
        "  {:>5} {:>10} {:>10} {:>9} {:>9} {:>10} {:>10} {:>10}",
        "level", "triangles", "receivers", "edge px", "error px", "light ms", "camera ms", "FLIP"
    );
    let mut renderers: Vec<(Renderer, Force)> = (0..count)
        .map(|l| {
            let force = Force { level: Some(l), one_tap: Some(false), ..Force::default() };
            (default_renderer(gpu, Overrides::default()), force)
        })
        .collect();
    let light = side_by_side(&mut renderers, Change::Light(0), FRAMES);
    let camera = side_by_side(&mut renderers, Change::Camera, FRAMES);
    let view = renderers[0].0.view();
    for l in 0..count {
        let sum = |f: &dyn Fn(&translucent::scene::needs::LevelFacts) -> usize| -> usize {
            facts.iter().map(|o| f(&o.levels[l.min(o.levels.len() - 1)])).sum()
        };
        let bunny = facts.iter().max_by_key(|o| o.levels.len()).expect("an object");
        let level = &bunny.levels[l.min(bunny.levels.len() - 1)];
        let px = view.pixel_footprint(glam::Vec3::from(bunny.center).distance(view.eye) as f64);
        println!(
            "  {l:>5} {:>10} {:>10} {:>9.2} {:>9.3} {:>10.1} {:>10.1} {:>10.4}",
            sum(&|f| f.triangles),
            sum(&|f| f.vertices),
            level.mean_edge / px,
            level.error / px,
            light[l].0,
            camera[l].0,
            flip(&camera[0].1, &camera[l].1)
        );
    }
}

/// What each term of the shading pass costs: camera-only frames (shade and tone map) side by
/// side, each with one term left out, with every saving on; the FLIP mean says what the term
/// does to the image.
fn terms(gpu: &Arc<Gpu>) {
    use translucent::render::shade::{TERM_ALL, TERM_FRESNEL, TERM_SHADOW, TERM_SPECULAR};
    let rows = [
        ("every term", 0),
        ("no shadow lookup", TERM_SHADOW),
        ("no GGX specular", TERM_SPECULAR),
        ("no Fresnel transmittance", TERM_FRESNEL),
        ("inputs only (raster, interpolation)", TERM_ALL),
    ];
    let mut renderers: Vec<(Renderer, Force)> = rows
        .iter()
        .map(|&(_, skip)| (default_renderer(gpu, Overrides::default()), Force { skip_terms: skip, ..Force::default() }))
        .collect();
    let camera = side_by_side(&mut renderers, Change::Camera, GATHER_FRAMES);
    println!(
        "\nShading terms, default scene 512x512, every saving on, camera-only frames side by side (median of \
         {GATHER_FRAMES}):"
    );
    println!("  {:<38} {:>10} {:>12} {:>10} {:>12}", "", "frame ms", "term costs", "FLIP", "shade ms (ts)");
    for (i, (name, _)) in rows.iter().enumerate() {
        println!(
            "  {name:<38} {:>10.1} {:>12.1} {:>10.4} {:>12.2}",
            camera[i].0,
            camera[0].0 - camera[i].0,
            flip(&camera[0].1, &camera[i].1),
            camera[i].2
        );
    }
}

/// Sections to run: those named on the command line (`cargo bench --bench render -- hierarchy`),
/// or all.
/// Median wall time of frames that follow `change` (the key light or the camera orbiting 3
/// degrees a frame) in two renderers side by side, alternating: `planned` records what its plan
/// asks for, `forced` records every pass for every object each frame, every channel gathered.
fn planned_against_forced(planned: &mut Renderer, forced: &mut Renderer, change: Change) -> (f64, f64) {
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for frame in 0..WARM_UP + FRAMES {
        for (renderer, times, force) in [(&mut *planned, &mut a, false), (&mut *forced, &mut b, true)] {
            step(renderer, change);
            let plan = renderer.plan(if force { Change::Everything } else { change });
            let start = Instant::now();
            renderer.frame(&plan).expect("frame");
            if frame >= WARM_UP {
                times.push(start.elapsed().as_secs_f64() * 1e3);
            }
        }
    }
    (median(&mut a), median(&mut b))
}

/// Relative RMSE of channel `c` of `a` against `b` (linear HDR, RGBA).
fn channel_rmse(a: &[f32], b: &[f32], c: usize) -> f64 {
    let (mut e, mut n) = (0.0f64, 0.0f64);
    for (pa, pb) in a.chunks(4).zip(b.chunks(4)) {
        e += (pa[c] as f64 - pb[c] as f64).powi(2);
        n += (pb[c] as f64).powi(2);
    }
    (e / n.max(1e-300)).sqrt()
}

/// A ball of radius 0.5 units in `material` at `mm_per_unit`, 256x256, one key light.
fn ball(material: &str, mm_per_unit: f64) -> String {
    format!(
        r#"
[camera]
eye = [0.0, 0.6, 2.4]
target = [0.0, 0.0, 0.0]
fov_y = 30.0
resolution = [256, 256]

[[object]]
shape = {{ type = "sphere", radius = 0.5, divisions = 64 }}
material = {{ type = "translucent", preset = "{material}", mm_per_unit = {mm_per_unit} }}
casts_shadow = false

[[light]]
type = "directional"
direction = [0.3, 0.8, 0.5]
irradiance = [1.0, 1.0, 1.0]

[sampling]
method = "turk"
count = 400
seed = 1
"#
    )
}

/// The planner's savings (frames it plans against the same frames with every pass forced), and
/// the measurement behind its local-or-gather thresholds.
fn planner(gpu: &Arc<Gpu>) {
    use translucent::render::plan::Transport;
    use translucent::scene::TransportMode;
    let open = |path: &str, transport: TransportMode| {
        let scene = match path {
            "" => Scene::builtin(),
            p => Scene::load(std::path::Path::new(p)).expect("scene"),
        };
        let overrides = Overrides { transport: Some(transport), resolution: Some([512, 512]), ..Default::default() };
        let mut r = Renderer::new(gpu, PreparedScene::new(&scene, &overrides).expect("scene")).expect("renderer");
        r.frame(&r.plan(Change::Everything)).expect("first frame");
        r
    };
    println!(
        "
Planner against every pass forced on (every channel gathered), 512x512, frames side by side:"
    );
    println!("  {:<34} {:<16} {:>11} {:>11} {:>8}", "scene", "change", "planned ms", "forced ms", "speed-up");
    for (name, path) in
        [("default scene", ""), ("ketchup ball 1 m (ketchup-metre)", "assets/scenes/ketchup-metre.toml")]
    {
        let mut planned = open(path, TransportMode::Auto);
        let mut forced = open(path, TransportMode::Gather);
        for (what, change) in [("key light moves", Change::Light(0)), ("camera moves", Change::Camera)] {
            let (p, f) = planned_against_forced(&mut planned, &mut forced, change);
            println!("  {name:<34} {what:<16} {p:>11.1} {f:>11.1} {:>7.1}x", f / p);
        }
    }

    println!(
        "
Local against a dense gather, per channel: relative RMSE of the local image against a 12,800-sample \
         vertex gather (ball of radius 0.5 units, 256x256). r: profile RMS radius, p: pixel footprint, s: sample \
         spacing at 400 samples; the planner's choice (local when r <= p or 4 r <= s):"
    );
    println!(
        "  {:<9} {:>8} {:>3} {:>9} {:>9} {:>11} {:>8}",
        "material", "diameter", "ch", "r / p", "s / r", "RMSE local", "planner"
    );
    for material in ["ketchup", "marble", "skimmilk"] {
        for mm_per_unit in [1000.0, 100.0, 20.0] {
            let text = ball(material, mm_per_unit);
            let scene = Scene::parse(&text, "ball.toml", None).expect("scene");
            let render = |overrides: Overrides| {
                let mut r =
                    Renderer::new(gpu, PreparedScene::new(&scene, &overrides).expect("scene")).expect("renderer");
                let plan = r.plan(Change::Everything);
                r.frame(&plan).expect("frame");
                (r.hdr_image().expect("image"), plan, r.needs().objects[0].clone())
            };
            let (local, _, _) = render(Overrides { transport: Some(TransportMode::Local), ..Default::default() });
            let (_, auto, facts) = render(Overrides::default());
            let dense =
                Overrides { transport: Some(TransportMode::Gather), samples: Some(12_800), ..Default::default() };
            let (reference, _, _) = render(dense);
            let p = auto.objects[0].pixel_footprint.unwrap_or(f64::NAN);
            for c in 0..3 {
                let r = facts.channels.as_ref().expect("translucent")[c].profile_radius;
                let choice = match auto.objects[0].channels[c].transport {
                    Transport::Local => "local",
                    Transport::Gather => "gather",
                };
                println!(
                    "  {material:<9} {:>6.0}mm {:>3} {:>9.2} {:>9.2} {:>11.4} {:>8}",
                    mm_per_unit,
                    ["R", "G", "B"][c],
                    r / p,
                    facts.sample_spacing / r,
                    channel_rmse(&local, &reference, c),
                    choice
                );
            }
        }
    }
}

fn wanted(section: &str) -> bool {
    let named: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    named.is_empty() || named.iter().any(|n| n == section)
}

fn main() {
    // TRANSLUCENT_VALIDATION=1 checks the benchmark's own passes (the yardsticks record their own
    // barriers); TRANSLUCENT_SYNC_VALIDATION=1 adds synchronisation validation. Off for figures.
    let on = |name: &str| std::env::var(name).is_ok_and(|v| !v.is_empty() && v != "0");
    let options = GpuOptions {
        device: std::env::var("TRANSLUCENT_DEVICE").ok(),
        validation: on("TRANSLUCENT_VALIDATION") || on("TRANSLUCENT_SYNC_VALIDATION"),
        sync_validation: on("TRANSLUCENT_SYNC_VALIDATION"),
        ..Default::default()
    };
    let gpu = Gpu::new(&options).expect("a Vulkan device (run `bash scripts/setup`)");
    println!("device: {} ({}, {} {})", gpu.info().name, gpu.info().kind, gpu.info().driver, gpu.info().driver_info);
    println!("cores: {}", std::thread::available_parallelism().map(|n| n.get()).unwrap_or(0));

    let scene = Scene::builtin();
    let overrides = Overrides { resolution: Some([512, 512]), ..Default::default() };
    let prepared = PreparedScene::new(&scene, &overrides).expect("default scene");
    println!(
        "default scene at 512x512: {} vertices, {} samples ({}), {} lights, {} shadow maps of {}^2",
        prepared.vertex_count(),
        prepared.sample_count(),
        prepared.scene.file.sampling.method,
        prepared.lights.len(),
        prepared.shadow_layers,
        prepared.scene.file.render.shadow_map_size
    );
    if wanted("frames") {
        frames(&gpu, prepared);
    }
    if wanted("savings") {
        savings(&gpu);
    }
    if wanted("levels") {
        levels(&gpu);
    }
    if wanted("terms") {
        terms(&gpu);
    }
    if wanted("hierarchy") {
        hierarchy(&gpu);
    }
    if wanted("growth") {
        growth::growth(&gpu);
    }
    if wanted("models") {
        models::models(&gpu);
    }
    if wanted("transport") {
        models::transport(&gpu);
    }
    if wanted("receivers") {
        receivers::receivers(&gpu);
    }
    if wanted("planner") {
        planner(&gpu);
    }
    if wanted("gathers") {
        gathers(&gpu, &scene);
        fps_against_samples(&gpu, &scene);
    }
    if gpu.validation_enabled() {
        let messages = gpu.validation().messages();
        println!("validation: {} messages", messages.len());
        for m in &messages {
            println!("  {m}");
        }
        assert!(messages.is_empty(), "the benchmark's passes raised validation messages");
    }
}

/// The "frames" section: per-pass times of the default scene with the key light moving and with
/// only the camera moving, its device memory, and the flat vertex gather against the naive
/// shader on the same renderer (so both see the same vertex-sample pairs).
fn frames(gpu: &Arc<Gpu>, prepared: PreparedScene) {
    let mut renderer = Renderer::new(gpu, prepared).expect("renderer");
    renderer.frame(&renderer.plan(Change::Everything)).expect("first frame");
    print(
        "key light moves every frame (its shadow map, splat, gather, shade, tone map):",
        &measure(&mut renderer, Change::Light(0)),
    );
    print("only the camera moves (shade, tone map):", &measure(&mut renderer, Change::Camera));
    // The allocator counts the device's whole use: the renderer's own is read before the
    // yardsticks allocate their targets.
    let own = renderer.device_memory();
    let mut roof = Roofline::new(gpu, &renderer);
    for (title, change) in [("key light moving", Change::Light(0)), ("camera moving", Change::Camera)] {
        let (frame, yard, pairs) = against_roofline(&mut renderer, &mut roof, change);
        print_roofline(title, &frame, &yard, pairs, change);
    }
    let mib = |bytes: u64| bytes as f64 / (1 << 20) as f64;
    println!(
        "device memory in use: {:.1} MiB by the renderer, {:.1} MiB with the yardsticks' targets",
        mib(own),
        mib(renderer.device_memory())
    );
    let (ours, naive, pairs) = gather_against_naive(gpu, &mut renderer);
    println!(
        "\nFlat vertex gather against a naive point-kernel shader (glsl/bench/gather_naive.comp), same {:.1}M \
         pairs, isolated submissions, alternating:",
        pairs / 1e6
    );
    println!("  ours  {ours:>8.1} ms = {:>7.1} Mpairs/s", pairs / ours / 1e3);
    println!("  naive {naive:>8.1} ms = {:>7.1} Mpairs/s", pairs / naive / 1e3);
    println!("  throughput ratio ours / naive = {:.2}", naive / ours);
}

/// The first half of the "gathers" section: each gather's time with the key light moving, and
/// how far its image is from the vertex gather's (the first, so the reference).
fn gathers(gpu: &Arc<Gpu>, scene: &Scene) {
    println!("\nWhere the gather runs: time against difference from the vertex gather (key light moving, 512x512):");
    println!(
        "  {:<12} {:>12} {:>12} {:>10} {:>22}",
        "gather", "gather ms", "frame ms", "frames/s", "image diff (of 255)"
    );
    let mut reference_image: Option<Vec<u8>> = None;
    for gather in [GatherMode::Vertex, GatherMode::Hierarchical, GatherMode::Sparse, GatherMode::Pixel] {
        let overrides = Overrides { gather: Some(gather), resolution: Some([512, 512]), ..Default::default() };
        let prepared = PreparedScene::new(scene, &overrides).expect("scene");
        let mut renderer = Renderer::new(gpu, prepared).expect("renderer");
        renderer.frame(&renderer.plan(Change::Everything)).expect("first frame");
        let image = renderer.image().expect("image").0;
        let m = measure(&mut renderer, Change::Light(0));
        let gather_ms = m.passes.iter().find(|(n, _, _)| n == "gather").map(|p| p.2).unwrap_or(0.0);
        let diff = match &reference_image {
            None => {
                reference_image = Some(image);
                0.0
            }
            Some(reference) => {
                reference.iter().zip(&image).map(|(a, b)| a.abs_diff(*b) as f64).sum::<f64>() / image.len() as f64
            }
        };
        println!(
            "  {gather:<12} {gather_ms:>12.1} {:>12.1} {:>10.2} {diff:>22.3}",
            m.frame_wall_ms,
            1000.0 / m.frame_wall_ms
        );
    }
}

/// The second half of the "gathers" section: the seed paper's Figure 7, frames per second
/// against sample count for each sampler, the key light moving every frame, and beside it the
/// system the seed compares itself with: Chang et al. 2008's texture-space gather against its
/// draws per receiver (atlas 256). Each point's error is beside it: the per-vertex relative RMS
/// over lit vertices (above 1% of the peak), mean of r, g, b, against the scene's own
/// configuration (its 1% error target: 30,686 Turk samples, hierarchical gather at epsilon 0.3,
/// 0.91% from the exact integral, README), all with every vertex gathered.
fn fps_against_samples(gpu: &Arc<Gpu>, scene: &Scene) {
    let reference = full_exitance(gpu, scene, &Overrides::default());
    println!("\nFPS against sample count (key light moving every frame, 512x512), seed Figure 7:");
    println!(
        "  {:<8} {:>8} {:>12} {:>12} {:>10} {:>9}",
        "sampler", "samples", "gather ms", "frame ms", "frames/s", "error %"
    );
    let seed = [Method::Turk, Method::Feature].into_iter().flat_map(|m| {
        [100, 200, 400, 800, 1600]
            .map(|n| (m.name(), n, Overrides { samples: Some(n), sampler: Some(m), ..Default::default() }))
    });
    let chang = [16, 64, 256, 1024].map(|n| {
        (
            "texture",
            n,
            Overrides { gather: Some(GatherMode::Texture), texture_samples: Some(n as u32), ..Default::default() },
        )
    });
    for (name, count, overrides) in seed.chain(chang) {
        let timed = Overrides { resolution: Some([512, 512]), ..overrides.clone() };
        let prepared = PreparedScene::new(scene, &timed).expect("scene");
        let mut renderer = Renderer::new(gpu, prepared).expect("renderer");
        renderer.frame(&renderer.plan(Change::Everything)).expect("first frame");
        let m = measure(&mut renderer, Change::Light(0));
        drop(renderer);
        let error = relative_rms(&full_exitance(gpu, scene, &overrides), &reference);
        let gather = m.passes.iter().find(|(n, _, _)| n == "gather").map(|p| p.2).unwrap_or(0.0);
        println!(
            "  {name:<8} {count:>8} {gather:>12.1} {:>12.1} {:>10.2} {:>9.2}",
            m.frame_wall_ms,
            1000.0 / m.frame_wall_ms,
            100.0 * error
        );
    }
}

/// Object 0's exitance at every vertex after one full frame of `scene` with `overrides` (at
/// 512x512, every vertex gathered).
fn full_exitance(gpu: &Arc<Gpu>, scene: &Scene, overrides: &Overrides) -> Vec<[f32; 3]> {
    let full = Overrides { resolution: Some([512, 512]), level_of_detail: Some(false), ..overrides.clone() };
    let prepared = PreparedScene::new(scene, &full).expect("scene");
    let mut renderer = Renderer::new(gpu, prepared).expect("renderer");
    renderer.frame(&renderer.plan(Change::Everything)).expect("frame");
    renderer.exitance(0).expect("exitance")
}

/// Per channel, the relative RMS of `got` against `reference` over the vertices above 1% of the
/// channel's peak; the mean of the three.
fn relative_rms(got: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    let per_channel = |c: usize| {
        let peak = reference.iter().map(|m| f64::from(m[c])).fold(0.0, f64::max);
        let lit: Vec<(f64, f64)> = got
            .iter()
            .zip(reference)
            .map(|(g, r)| (f64::from(g[c]), f64::from(r[c])))
            .filter(|&(_, r)| r > 0.01 * peak)
            .collect();
        (lit.iter().map(|(g, r)| ((g - r) / r).powi(2)).sum::<f64>() / lit.len().max(1) as f64).sqrt()
    };
    (0..3).map(per_channel).sum::<f64>() / 3.0
}

/// A frame against the roofline: its median timestamp per pass, and its median wall time from
/// recording to the fence.
struct RooflineFrame {
    passes: Vec<(String, f64)>,
    wall: f64,
}

/// Frames following `change`, each followed by a run of the yardsticks (so outside load falls
/// on both alike): the frame's medians, the yardsticks' medians, and the vertex-sample pairs a
/// flat gather of the frame would sum.
fn against_roofline(renderer: &mut Renderer, roof: &mut Roofline, change: Change) -> (RooflineFrame, Yardsticks, f64) {
    let mut stamps: Vec<(String, Vec<f64>)> = Vec::new();
    let mut walls = Vec::new();
    let mut pairs = 0.0;
    for frame in 0..WARM_UP + GATHER_FRAMES {
        step(renderer, change);
        let plan = renderer.plan(change);
        let start = Instant::now();
        let timings = renderer.frame(&plan).expect("frame");
        let wall = start.elapsed().as_secs_f64() * 1e3;
        roof.run(renderer, &plan);
        pairs = roofline::frame_pairs(renderer, &plan);
        if frame < WARM_UP {
            continue;
        }
        walls.push(wall);
        for (pass, ms) in timings.passes {
            let name = pass.name().to_string();
            match stamps.iter_mut().find(|(n, _)| *n == name) {
                Some((_, v)) => v.push(ms),
                None => stamps.push((name, vec![ms])),
            }
        }
    }
    let passes = stamps.into_iter().map(|(n, mut v)| (n, median(&mut v))).collect();
    (RooflineFrame { passes, wall: median(&mut walls) }, roof.yardsticks(), pairs)
}

/// Each pass against its yardstick, and the frame against the roofline's sum.
fn print_roofline(title: &str, frame: &RooflineFrame, yard: &Yardsticks, pairs: f64, change: Change) {
    let light = matches!(change, Change::Light(_));
    let passes = &frame.passes;
    println!(
        "\nRoofline, {title} (timestamps, median of {GATHER_FRAMES} frames, each followed by the yardsticks; \
         submission: wall time of an empty one):"
    );
    println!("  {:<8} {:>10} {:>13} {:>7}  yardstick", "pass", "frame ms", "yardstick ms", "ratio");
    let yardstick = |name: &str| match name {
        "shade" => Some((yard.raster, "trivial shaders, same geometry and targets")),
        "shadow" => Some((yard.shadow, "casters depth-only into one map")),
        "tonemap" => Some((yard.tonemap, "texel fetch, clamp, pack")),
        "gather" => Some((yard.gather, "naive kernel, same pair count as a flat gather")),
        _ => None,
    };
    let mut total = 0.0;
    for (name, ms) in passes {
        total += ms;
        match yardstick(name) {
            Some((y, what)) => println!("  {name:<8} {ms:>10.2} {y:>13.2} {:>7.2}  {what}", ms / y),
            None => println!("  {name:<8} {ms:>10.2} {:>13} {:>7}", "-", "-"),
        }
    }
    println!(
        "  (the raster yardstick with the shading pass's vertex stage and its four interpolants read: {:.2} ms)",
        yard.raster_inputs
    );
    let shade = passes.iter().find(|(n, _)| n == "shade").map_or(0.0, |p| p.1);
    println!(
        "  (deferred: a G-buffer of those interpolants {:.2} ms + the shading arithmetic in compute over its \
         pixels {:.2} ms = {:.2} ms, {:.2}x the shade pass)",
        yard.gbuffer,
        yard.shade_compute,
        yard.gbuffer + yard.shade_compute,
        (yard.gbuffer + yard.shade_compute) / shade
    );
    let roof = if light { yard.light() } else { yard.camera() };
    // The frame's submission: its wall time past its passes' timestamps (recording, submission,
    // the fence), as the roofline counts an empty submission's wall time. On lavapipe the
    // timestamps take in nearly all of it; on a hardware GPU the fence's round trip can exceed
    // the passes.
    let submit = (frame.wall - total).max(0.0);
    total += submit;
    println!(
        "  {:<8} {submit:>10.2} {:>13.2}  (the frame: wall time {:.2} ms, past its passes)",
        "submit", yard.submit, frame.wall
    );
    println!(
        "  frame    {total:>10.2} {roof:>13.2} {:>7.2}  = {:.0} frames/s against {:.0} at the roofline{}",
        total / roof,
        1e3 / total,
        1e3 / roof,
        if light { format!(" ({:.1}M pairs in the naive gather)", pairs / 1e6) } else { String::new() }
    );
}

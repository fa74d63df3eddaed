//! translucent embedded in a host engine (examples/embed.rs, raw ash): the host's device and
//! command buffer, the host's colour and depth images, on lavapipe with the host's validation
//! messenger on. Runs are serialised: the example counts validation messages process-wide.

mod common;
#[path = "../examples/embed.rs"]
#[allow(dead_code)]
mod embed;

use ash::vk;
use embed::{GROUND, Options, SIZE, SPHERE_SCENE};
use std::sync::Mutex;
use translucent::render::plan::Pass;
use translucent::render::tonemap::display_value;

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn run(options: &Options) -> Result<embed::Run, String> {
    let _guard = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: tests in this file set the same value; the example reads it once per run.
    unsafe { std::env::set_var("TRANSLUCENT_VALIDATION", "1") };
    let result = embed::run(options);
    let messages = embed::validation_messages();
    assert_eq!(messages, 0, "the host's validation messenger counted {messages} messages");
    result
}

fn is_ground(p: &[f32]) -> bool {
    p.iter().zip(GROUND).all(|(a, b)| (a - b).abs() < 1e-6)
}

/// The engine's first frame against the CLI's render of the same scene and view, where both
/// draw the same thing: the mean difference in 8-bit display levels, and how many sphere pixels
/// of the CLI's the engine's quad hides.
fn against_the_cli(run: &embed::Run, name: &str) -> (f64, u64) {
    let dir = common::temp_dir(name);
    let scene = dir.join("sphere.toml");
    std::fs::write(&scene, SPHERE_SCENE).unwrap();
    let exr = dir.join("cli.exr");
    let png = dir.join("cli.png");
    let args = ["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap(), "--exr", exr.to_str().unwrap()];
    let out = common::translucent(&args, &[]);
    assert!(out.status.success(), "{}", common::text(&out.stderr));
    let cli = image::open(&exr).unwrap().to_rgba32f().into_raw();
    let host = &run.frames[0].linear;
    assert_eq!(cli.len(), host.len());
    let (mut sum, mut compared, mut hidden) = (0u64, 0u64, 0u64);
    for (c, h) in cli.chunks(4).zip(host.chunks(4)) {
        if is_ground(h) {
            // The host's quad, in front of the sphere where the CLI draws the sphere.
            hidden += (c[0] > 0.0) as u64;
            continue;
        }
        for k in 0..3 {
            sum += (display_value(c[k] as f64, 1.0) as i64 - display_value(h[k] as f64, 1.0) as i64).unsigned_abs();
        }
        compared += 3;
    }
    let mean = sum as f64 / compared as f64;
    eprintln!(
        "{name}: {compared} channels compared, mean difference {mean:.4}/255; {hidden} sphere pixels hidden by the host's quad"
    );
    (mean, hidden)
}

#[test]
fn an_embedded_frame_is_clean_and_matches_the_cli_where_both_draw_the_same() {
    let run = run(&Options::default()).expect("embedded run");
    let (mean, hidden) = against_the_cli(&run, "embed-cli");
    assert!(mean <= 1.0, "mean difference {mean:.3}/255 from the CLI's render");
    assert!(hidden > 0, "the host's quad hides no part of the sphere: no depth test against the host's depth");
    let host = &run.frames[0].linear;
    let lit = host.chunks(4).filter(|p| !is_ground(p) && p[0] > 0.05).count();
    assert!(lit > (SIZE * SIZE / 20) as usize, "only {lit} sphere pixels");
    assert!(!run.frames[0].timings.is_empty(), "timings read after the host's fence");
}

#[test]
fn a_reversed_z_engine_matches_the_cli_and_its_quad_hides_the_sphere_as_the_standard_one_does() {
    let reversed = run(&Options { depth: translucent::DepthTest::REVERSED, frames: 1, ..Options::default() })
        .expect("embedded run, reversed-Z");
    let (mean, hidden) = against_the_cli(&reversed, "embed-cli-reversed");
    assert!(mean <= 1.0, "mean difference {mean:.3}/255 from the CLI's render");
    let standard = run(&Options { frames: 1, ..Options::default() }).expect("embedded run");
    let (_, standard_hidden) = against_the_cli(&standard, "embed-cli-standard");
    assert_eq!(hidden, standard_hidden, "the quad hides another part of the sphere under reversed-Z");
    assert!(hidden > 0, "the quad hides nothing: no depth test against the engine's reversed-Z depth");
}

#[test]
fn a_camera_move_records_only_shading_and_the_image_follows() {
    let run = run(&Options::default()).expect("embedded run");
    let first = &run.frames[0].passes;
    assert!(first.contains(&Pass::Splat) && first.contains(&Pass::Gather) && first.contains(&Pass::Shade));
    assert!(!first.contains(&Pass::Tonemap), "the host tone-maps its own target");
    for frame in &run.frames[1..] {
        assert_eq!(frame.passes, [Pass::Shade], "a camera move re-records only shading");
    }
    let changed = run.frames[0].linear.iter().zip(&run.frames[1].linear).filter(|(a, b)| a != b).count();
    assert!(changed > 100, "the view did not change ({changed} values differ)");
}

#[test]
fn two_renderers_share_the_host_device_and_command_buffer() {
    let run = run(&Options { second_renderer: true, frames: 2, ..Options::default() }).expect("embedded run");
    let frame = &run.frames[0].linear;
    // The ketchup sphere (second renderer) is red; the marble (first) is grey-white.
    let red = frame.chunks(4).filter(|p| !is_ground(p) && p[0] > 0.02 && p[0] > 3.0 * p[1]).count();
    let grey = frame.chunks(4).filter(|p| !is_ground(p) && p[1] > 0.05 && (p[0] - p[1]).abs() < 0.2 * p[0]).count();
    assert!(red > 20 && grey > 100, "red (ketchup) {red}, grey (marble) {grey} pixels");
}

#[test]
fn dropping_the_renderer_leaves_the_host_device_usable() {
    let run = run(&Options { frames: 1, ..Options::default() }).expect("embedded run");
    let ground = run.after_drop.chunks(4).filter(|p| is_ground(p)).count();
    let other = run.after_drop.chunks(4).filter(|p| !is_ground(p) && p[..3].iter().any(|v| *v != 0.0)).count();
    assert!(ground > 100, "the host drew its quad again ({ground} pixels)");
    assert_eq!(other, 0, "something of translucent's was drawn after it was dropped");
}

#[test]
fn a_host_device_without_the_required_features_gets_a_clear_error() {
    let error = run(&Options { shader_output_layer: false, ..Options::default() }).err().expect("refused");
    assert!(error.contains("shaderOutputLayer") && error.contains("required_features"), "{error}");
    let error = run(&Options { api_version: vk::API_VERSION_1_2, ..Options::default() }).err().expect("refused");
    assert!(error.contains("apiVersion 1.3"), "{error}");
}

#[test]
fn unusable_host_targets_are_refused_with_the_reason() {
    let scene = translucent::Scene::parse(SPHERE_SCENE, "sphere", None).unwrap();
    let prepared = translucent::PreparedScene::new(&scene, &Default::default()).unwrap();
    common::with_gpu(|gpu| {
        let host = |color_format, depth_format| translucent::TargetDesc::Host { color_format, depth_format };
        let refused = |target, prepared: &translucent::PreparedScene| {
            translucent::Renderer::with_target(gpu, prepared.clone(), target).err().expect("refused").to_string()
        };
        let error = refused(host(vk::Format::D32_SFLOAT, vk::Format::D32_SFLOAT), &prepared);
        assert!(error.contains("colour format"), "{error}");
        let error = refused(host(vk::Format::R8G8B8A8_UNORM, vk::Format::R8G8B8A8_UNORM), &prepared);
        assert!(error.contains("depth format"), "{error}");
        let mut pixel = prepared.clone();
        pixel.scene.file.render.gather = translucent::GatherMode::Pixel;
        let error = refused(host(vk::Format::R16G16B16A16_SFLOAT, vk::Format::D32_SFLOAT), &pixel);
        assert!(error.contains("pixel gather"), "{error}");
    });
}

//! The planner's claims, checked by counting what frames really record (`Gpu::recorded`: every
//! dispatch and draw, per shader) rather than by reading the plan: a scene simulates only what
//! it calls for, and a frame redoes only what its change invalidates.

mod common;

use common::*;
use glam::Vec3;
use std::sync::Arc;
use translucent::SceneEdit;
use translucent::gpu::{Gpu, RecordCounts};
use translucent::optics::Material;
use translucent::render::plan::{BakedLevels, Change, LevelReason, SplatLights, Transport};
use translucent::render::renderer::Renderer;
use translucent::scene::build::{Overrides, PreparedScene, ResolvedMaterial};
use translucent::scene::{MaterialSpec, Scene, Transform, TransportMode, lights};

/// Whole meshes unless the test asks for levels of detail: the counts below are of the passes a
/// change calls for, and the exitance read back is every vertex's.
fn prepare(text: &str, overrides: &Overrides) -> PreparedScene {
    let overrides = Overrides { level_of_detail: overrides.level_of_detail.or(Some(false)), ..overrides.clone() };
    PreparedScene::new(&Scene::parse(text, "planner.toml", None).unwrap(), &overrides).unwrap()
}

/// Render the frame the renderer's pending change calls for; what it recorded.
fn frame(gpu: &Arc<Gpu>, renderer: &mut Renderer) -> RecordCounts {
    let before = gpu.recorded();
    let change = renderer.pending_change().unwrap_or(Change::Camera);
    renderer.frame(&renderer.plan(change)).unwrap();
    gpu.recorded().since(&before)
}

/// A sphere of `radius` at `center` made of `material`, for a scene's object list.
fn sphere(radius: f32, center: [f32; 3], material: &str, mm_per_unit: f64, casts: bool) -> String {
    format!(
        r#"
[[object]]
shape = {{ type = "sphere", radius = {radius}, divisions = 24 }}
transform = {{ translate = [{}, {}, {}] }}
material = {{ type = "translucent", preset = "{material}", mm_per_unit = {mm_per_unit} }}
casts_shadow = {casts}
"#,
        center[0], center[1], center[2]
    )
}

/// A camera at `eye` looking at the origin, `resolution` pixels square, and one key light from
/// above-front.
fn stage(eye: [f32; 3], resolution: u32) -> String {
    format!(
        r#"
[camera]
eye = [{}, {}, {}]
target = [0.0, 0.0, 0.0]
fov_y = 30.0
resolution = [{resolution}, {resolution}]

[[light]]
type = "directional"
direction = [0.3, 0.8, 0.5]
irradiance = [1.0, 1.0, 1.0]

[sampling]
method = "turk"
count = 200
"#,
        eye[0], eye[1], eye[2]
    )
}

#[test]
fn an_opaque_only_scene_dispatches_no_compute_but_the_tone_map() {
    let text = format!(
        "{}\n[[object]]\nshape = {{ type = \"sphere\", radius = 1.0, divisions = 12 }}\nmaterial = {{ type = \"opaque\", \
         albedo = [0.5, 0.5, 0.5] }}\n",
        stage([0.0, 0.0, 6.0], 32)
    );
    with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, prepare(&text, &Overrides::default())).unwrap();
        let counts = frame(gpu, &mut renderer);
        // The tone map turns the HDR image into the readable one; nothing else computes.
        assert_eq!(counts.dispatches(), counts.get("tonemap.comp"), "{counts:?}");
        assert_eq!(counts.get("tonemap.comp"), 1);
        assert!(counts.get("shade.vert") == 1 && counts.get("shadow.vert") == 1, "{counts:?}");
        // No samples, so nothing splatted to read back: the command line's check of every
        // render for non-finite values failed here on the splat buffer's 16 bytes.
        assert!(renderer.splat_irradiance().unwrap().is_empty());
        assert!(renderer.find_non_finite().unwrap().is_empty());
    });
}

#[test]
fn a_camera_orbit_splats_and_gathers_once_while_the_view_changes() {
    let text = format!("{}{}", stage([0.0, 0.02, 0.06], 48), sphere(0.01, [0.0; 3], "marble", 1000.0, true));
    with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, prepare(&text, &Overrides::default())).unwrap();
        let plan = renderer.plan(Change::Everything);
        assert!(plan.objects[0].channels.iter().all(|c| c.transport == Transport::Gather), "{plan}");
        let mut total = RecordCounts::default();
        let mut images = Vec::new();
        for i in 0..10 {
            if i > 0 {
                renderer.edit(SceneEdit::Camera(renderer.camera().orbited(Vec3::ZERO, 12.0))).unwrap();
            }
            let counts = frame(gpu, &mut renderer);
            for (k, v) in counts.0 {
                *total.0.entry(k).or_default() += v;
            }
            images.push(renderer.image().unwrap().0);
        }
        assert_eq!(total.get("splat.comp"), 1, "{total:?}");
        assert_eq!(total.get("gather.comp"), 1, "{total:?}");
        assert_eq!(total.get("shade.vert"), 10, "{total:?}");
        assert!(images.windows(2).all(|w| w[0] != w[1]), "the view did not change between frames");
    });
}

#[test]
fn a_moving_key_light_splats_and_gathers_every_frame_and_redraws_one_shadow_map() {
    let mut text = format!("{}{}", stage([0.0, 0.02, 0.06], 32), sphere(0.01, [0.0; 3], "marble", 1000.0, true));
    text.push_str("\n[[light]]\ntype = \"directional\"\ndirection = [-0.5, 0.6, 0.2]\nirradiance = [0.5, 0.5, 0.5]\n");
    with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, prepare(&text, &Overrides::default())).unwrap();
        let first = frame(gpu, &mut renderer);
        assert_eq!(first.get("shadow.vert"), 2, "two lights, one caster: {first:?}");
        for _ in 0..3 {
            let light = &renderer.scene().scene.file.lights[0];
            let moved = lights::orbit(light, Vec3::ZERO, 5.0).unwrap();
            renderer.edit(SceneEdit::Light { index: 0, light: moved }).unwrap();
            let counts = frame(gpu, &mut renderer);
            assert_eq!(counts.get("shadow.vert"), 1, "one map of one caster: {counts:?}");
            assert_eq!((counts.get("splat.comp"), counts.get("gather.comp")), (1, 1), "{counts:?}");
        }
    });
}

/// Relative RMSE of `a` against `b` over the pixels where `b` is lit (linear HDR, RGB).
fn relative_rmse(a: &[f32], b: &[f32]) -> f64 {
    let (mut err, mut norm) = (0.0f64, 0.0f64);
    for (pa, pb) in a.chunks(4).zip(b.chunks(4)) {
        for c in 0..3 {
            err += (pa[c] as f64 - pb[c] as f64).powi(2);
            norm += (pb[c] as f64).powi(2);
        }
    }
    (err / norm).sqrt()
}

#[test]
fn ketchup_at_metre_scale_goes_local_in_green_and_blue_and_matches_a_dense_gather() {
    // A 1 m ketchup ball: green and blue diffuse about a millimetre, far under a pixel (about
    // 4 mm here) and far under the sample spacing. The dipole in every channel: `"auto"` gives
    // the dark channels single scattering between points, which no local transport stands in for.
    let ball = sphere(0.5, [0.0; 3], "ketchup", 1000.0, false)
        .replace("mm_per_unit = 1000 }", "mm_per_unit = 1000, model = \"dipole\" }");
    assert!(ball.contains("model = \"dipole\""), "{ball}");
    let text = format!("{}{}", stage([0.0, 0.6, 2.4], 96), ball);
    with_gpu(|gpu| {
        let prepared = prepare(&text, &Overrides::default());
        let mut auto = Renderer::new(gpu, prepared).unwrap();
        let plan = auto.plan(Change::Everything);
        let o = &plan.objects[0];
        assert_eq!(o.channels[1].transport, Transport::Local, "{plan}");
        assert_eq!(o.channels[2].transport, Transport::Local, "{plan}");
        let before = gpu.recorded();
        auto.frame(&plan).unwrap();
        let counts = gpu.recorded().since(&before);
        if o.local_mask() == 0b111 {
            assert_eq!(counts.get("splat.comp") + counts.get("gather.comp"), 0, "all local: {counts:?}");
        }
        let local = auto.hdr_image().unwrap();
        drop(auto);
        let dense = Overrides { samples: Some(12_800), transport: Some(TransportMode::Gather), ..Overrides::default() };
        let mut gathered = Renderer::new(gpu, prepare(&text, &dense)).unwrap();
        gathered.frame(&gathered.plan(Change::Everything)).unwrap();
        let reference = gathered.hdr_image().unwrap();
        let e = relative_rmse(&local, &reference);
        println!("ketchup at 1 m, local ({:03b}) against a 12,800-sample gather: relative RMSE {e:.4}", o.local_mask());
        assert!(e < 0.02, "relative RMSE {e}");
    });
}

#[test]
fn marble_at_five_centimetres_is_gathered_in_every_channel() {
    let text = format!("{}{}", stage([0.0, 0.05, 0.15], 256), sphere(0.025, [0.0; 3], "marble", 1000.0, true));
    let prepared = prepare(&text, &Overrides { samples: Some(400), ..Overrides::default() });
    let camera = translucent::render::camera::CameraView::of_scene(&prepared);
    let view = translucent::render::plan::View::of_camera(&camera, 256);
    let needs = translucent::render::plan::needs(&prepared, false, Default::default());
    let plan = translucent::render::plan::Planner::new(1, Change::Everything).plan(&needs, &view);
    assert!(plan.objects[0].channels.iter().all(|c| c.transport == Transport::Gather), "{plan}");
}

#[test]
fn an_object_behind_the_camera_is_not_gathered_until_the_camera_turns_to_it() {
    // One ball in front of the eye (at the origin), one behind it.
    let text = format!(
        "{}{}{}",
        stage([0.0, 0.0, 0.1], 32),
        sphere(0.01, [0.0; 3], "marble", 1000.0, false),
        sphere(0.01, [0.0, 0.0, 0.2], "skimmilk", 1000.0, false)
    );
    with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, prepare(&text, &Overrides::default())).unwrap();
        let plan = renderer.plan(Change::Everything);
        assert!(plan.objects[0].in_view && !plan.objects[1].in_view, "{plan}");
        let counts = frame(gpu, &mut renderer);
        assert_eq!((counts.get("splat.comp"), counts.get("gather.comp")), (1, 1), "front ball only: {counts:?}");
        let behind = renderer.exitance(1).unwrap();
        assert!(behind.iter().all(|e| *e == [0.0; 3]), "the ball behind was gathered");
        // Turn round on the spot: the ball behind comes into view, stale, and is gathered.
        let eye = renderer.camera().eye;
        renderer.edit(SceneEdit::Camera(renderer.camera().orbited(eye, 180.0))).unwrap();
        let counts = frame(gpu, &mut renderer);
        assert_eq!((counts.get("splat.comp"), counts.get("gather.comp")), (1, 1), "back ball only: {counts:?}");
        assert!(renderer.exitance(1).unwrap().iter().any(|e| e[0] > 0.0), "the ball now in view has no exitance");
        // And once more: nothing stale, nothing gathered.
        renderer.edit(SceneEdit::Camera(renderer.camera().orbited(eye, 1.0))).unwrap();
        let counts = frame(gpu, &mut renderer);
        assert_eq!(counts.get("splat.comp") + counts.get("gather.comp"), 0, "{counts:?}");
    });
}

#[test]
fn a_material_change_regathers_the_same_samples_and_a_transform_change_resamples() {
    let text = format!("{}{}", stage([0.0, 0.02, 0.06], 32), sphere(0.01, [0.0; 3], "marble", 1000.0, true));
    with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, prepare(&text, &Overrides::default())).unwrap();
        frame(gpu, &mut renderer);
        let samples = renderer.scene().objects[0].samples.clone();
        let marble = renderer.exitance(0).unwrap();

        renderer.edit(SceneEdit::Material { object: 0, material: Material::preset("skimmilk").unwrap() }).unwrap();
        let counts = frame(gpu, &mut renderer);
        assert_eq!((counts.get("splat.comp"), counts.get("gather.comp")), (1, 1), "{counts:?}");
        assert_eq!(counts.get("shadow.vert"), 0, "a material does not move shadows: {counts:?}");
        assert_eq!(renderer.scene().objects[0].samples, samples, "resampled on a material change");
        assert_ne!(renderer.exitance(0).unwrap(), marble, "the new material changed nothing");

        let moved = Transform { translate: Some([0.002, 0.0, 0.0]), ..Transform::default() };
        renderer.edit(SceneEdit::Transform { object: 0, transform: moved }).unwrap();
        let counts = frame(gpu, &mut renderer);
        assert_eq!((counts.get("splat.comp"), counts.get("gather.comp")), (1, 1), "{counts:?}");
        assert_eq!(counts.get("shadow.vert"), 1, "geometry moved: shadows redrawn: {counts:?}");
        let resampled = &renderer.scene().objects[0].samples;
        assert_eq!(resampled.len(), samples.len());
        let shift = resampled[0].position - samples[0].position;
        assert!((shift - Vec3::new(0.002, 0.0, 0.0)).length() < 1e-6, "samples did not move with the object");
        assert_ne!(renderer.exitance(0).unwrap(), marble, "the move lost the new material");
        // One copy of the material, the prepared object's: the move kept it, and the file as
        // read still says marble.
        let ResolvedMaterial::Translucent { material, .. } = &renderer.scene().objects[0].material else {
            panic!("the sphere is translucent")
        };
        assert_eq!(*material, Material::preset("skimmilk").unwrap());
        let file = &renderer.scene().scene.file.objects[0].material;
        assert!(matches!(file, MaterialSpec::Translucent { preset: Some(p), .. } if p == "marble"), "{file:?}");
    });
}

#[test]
fn plan_prints_every_change_and_its_json_has_the_documented_fields() {
    let out = subcommand("plan", &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    for line in
        ["after a change of everything:", "after a change of camera:", "after a change of material of object 0:"]
    {
        assert!(stdout.contains(line), "{line} missing:\n{stdout}");
    }
    assert!(stdout.contains("profile radius") && stdout.contains("sample spacing"), "{stdout}");
    let out = subcommand("plan", &["--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["version"], 1);
    let frames = json["frames"].as_array().unwrap();
    assert!(frames.len() >= 6);
    for f in frames {
        for key in ["change", "passes", "skipped", "shadow_light", "objects"] {
            assert!(f.get(key).is_some(), "{key} missing from {f}");
        }
    }
    let bunny = &frames[0]["objects"][0];
    for key in ["object", "name", "in_view", "pixel_footprint", "channels", "splat", "gather", "why", "stale_after"] {
        assert!(bunny.get(key).is_some(), "{key} missing from {bunny}");
    }
    assert_eq!(bunny["channels"][0]["transport"], "gather");
    // docs/PHYSICS.md, "Which model a channel takes": the default model weighed the dipole's
    // predicted error against the light, over the 1% target on the bunny, so the kernel.
    let model = &bunny["model"]["channels"][0];
    assert_eq!(model["takes"], "kernel", "{model}");
    assert_eq!(model["reason"]["why"], "dipole_over_target", "{model}");
    assert!(model["dipole"]["error"].as_f64().is_some_and(|e| e > 0.01), "{model}");
    assert!(model["predicted"].as_f64().is_some_and(|e| e < model["dipole"]["error"].as_f64().unwrap()), "{model}");
    assert_eq!(bunny["transport"]["state"], "scales", "plan walks or reads the kernel it chose: {bunny}");
    assert!(json["objects"][0]["channels"][0]["profile_radius"].as_f64().unwrap() > 0.0);
    // docs/PLAN.md, "The sample count": the facts and each channel's terms.
    let density = &bunny["density"];
    for key in ["area", "curvature_radius", "occlusion", "edge_length"] {
        assert!(density["facts"][key].as_f64().is_some_and(|v| v > 0.0), "{key} missing from {density}");
    }
    for key in ["spacing_over_radius", "thin_term", "shadow_term", "facet_term", "error"] {
        assert!(density["predicted"][2][key].as_f64().is_some_and(|v| v > 0.0), "{key} missing from {density}");
    }
}

#[test]
fn plan_takes_an_error_target_and_a_tighter_one_places_more_samples() {
    // The study's sphere with its count left to the target (sphere-marble.toml names no count).
    let scene = repo_path("assets/scenes/sphere-marble.toml");
    let count_at = |target: &str| {
        let out = subcommand("plan", &[scene.to_str().unwrap(), "--json", "--max-error", target]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let density = &json["frames"][0]["objects"][0]["density"];
        assert_eq!(density["target"].as_f64(), Some(target.parse().unwrap()), "{density}");
        density["count"].as_u64().unwrap()
    };
    let (loose, tight) = (count_at("0.05"), count_at("0.01"));
    assert!(tight > loose, "1% placed {tight} samples, 5% {loose}");
    let out = subcommand("plan", &[scene.to_str().unwrap(), "--max-error", "2"]);
    let err = text(&out.stderr);
    assert!(!out.status.success() && err.contains("--max-error"), "{err}");
}

#[test]
fn levels_baked_from_sky_light_are_withdrawn_when_it_is_recomputed_and_offered_once_baked_again() {
    let overrides = Overrides { samples: Some(64), resolution: Some([64, 64]), ..Overrides::default() };
    let prepared = PreparedScene::new(&Scene::builtin(), &overrides).unwrap();
    with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, prepared).unwrap();
        // `frame` bakes after a frame that ran the vertex-light pass.
        frame(gpu, &mut renderer);
        assert_eq!(renderer.planner().baked_levels(), BakedLevels::Current);
        let baked = |r: &Renderer| r.needs().objects.iter().position(|o| o.levels.iter().any(|l| l.locked));
        let floor = baked(&renderer).expect("the floor's levels baked from the sky light");
        let count = renderer.needs().objects[floor].levels.len();
        // The sky light moves: the frame recomputing it draws the floor whole, and (recorded as a
        // host would, without baking) its baked levels are offered no more.
        let sky = renderer.needs().environment.expect("an environment light");
        let light = renderer.scene().scene.file.lights[sky].clone();
        renderer.edit(SceneEdit::Light { index: sky, light }).unwrap();
        let plan = renderer.plan(renderer.pending_change().unwrap());
        assert_eq!(plan.objects[floor].level_why, LevelReason::SkyLightRecomputed, "{plan}");
        gpu.one_shot("frame", |cmd| renderer.record_frame(cmd, None)).unwrap().unwrap();
        assert_eq!(renderer.planner().baked_levels(), BakedLevels::Withdrawn);
        assert_eq!(renderer.needs().objects[floor].levels.len(), 1);
        assert_eq!(renderer.plan(Change::Camera).objects[floor].level, 0);
        // Baked again: offered again.
        assert!(renderer.bake_static_levels().unwrap());
        assert_eq!(renderer.planner().baked_levels(), BakedLevels::Current);
        assert_eq!(renderer.needs().objects[floor].levels.len(), count);
    });
}

#[test]
fn a_moved_key_light_resplats_only_its_own_part_and_matches_a_full_splat() {
    // A sphere over a floor, lit by a key light and the sky (16 shadowed directions).
    let mut text = format!(
        "{}{}{}",
        stage([0.0, 0.02, 0.06], 32),
        sphere(0.01, [0.0; 3], "marble", 1000.0, true),
        sphere(0.004, [0.012, -0.004, 0.0], "skin1", 1000.0, true)
    );
    text.push_str("\n[[light]]\ntype = \"environment\"\nscale = 0.3\ndirections = 16\n");
    with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, prepare(&text, &Overrides::default())).unwrap();
        frame(gpu, &mut renderer);
        let light = lights::orbit(&renderer.scene().scene.file.lights[0], Vec3::ZERO, 40.0).unwrap();
        renderer.edit(SceneEdit::Light { index: 0, light }).unwrap();
        let plan = renderer.plan(renderer.pending_change().unwrap());
        for o in &plan.objects {
            assert!(o.splat, "{plan}");
            assert_eq!(o.splat_lights, SplatLights::KeyLights, "{plan}");
        }
        assert!(plan.to_string().contains("key lights only"), "{plan}");
        frame(gpu, &mut renderer);
        let kept = renderer.splat_irradiance().unwrap();
        // The same moved scene splatted whole by a new renderer.
        let mut fresh = Renderer::new(gpu, renderer.scene().clone()).unwrap();
        let first = fresh.plan(fresh.pending_change().unwrap());
        assert!(first.objects.iter().all(|o| o.splat_lights == SplatLights::All), "{first}");
        frame(gpu, &mut fresh);
        let full = fresh.splat_irradiance().unwrap();
        assert_eq!(kept.len(), full.len());
        let lit = full.iter().filter(|(e, _)| e.iter().any(|&v| v > 0.0)).count();
        assert!(lit > full.len() / 3, "most samples are lit: {lit} of {}", full.len());
        let mut worst = 0.0f32;
        for ((a, _), (b, _)) in kept.iter().zip(&full) {
            for c in 0..3 {
                worst = worst.max((a[c] - b[c]).abs() / b[c].abs().max(1e-12));
            }
        }
        eprintln!("kept against full splat: worst relative difference {worst:.2e}");
        assert!(worst <= 1e-6, "worst relative difference {worst:e}");
        // The near energy is kept with the environment's part, not recomputed: the exitance
        // gathered from the kept splat is the fresh renderer's too.
        let mut worst = 0.0f32;
        for object in 0..2 {
            let (a, b) = (renderer.exitance(object).unwrap(), fresh.exitance(object).unwrap());
            for (a, b) in a.iter().zip(&b) {
                for c in 0..3 {
                    worst = worst.max((a[c] - b[c]).abs() / b[c].abs().max(1e-12));
                }
            }
        }
        eprintln!("exitance from the kept splat against the full one: worst relative difference {worst:.2e}");
        assert!(worst <= 1e-6, "worst relative difference {worst:e}");
        // A material change re-splats that object whole.
        renderer.edit(SceneEdit::Material { object: 1, material: Material::preset("marble").unwrap() }).unwrap();
        let plan = renderer.plan(renderer.pending_change().unwrap());
        assert_eq!(plan.objects[1].splat_lights, SplatLights::All, "{plan}");
    });
}

/// `SceneEdit::Scene` (what the viewer's keys use): a renderer given the same file prepared with
/// another gather and error target computes everything again and draws exactly what a renderer
/// made for that preparation draws; its earlier frame's timings stay readable.
#[test]
fn a_renderer_given_another_preparation_draws_what_a_renderer_made_for_it_draws() {
    with_gpu(|gpu| {
        let scene = Scene::builtin();
        let first =
            Overrides { samples: Some(400), gather: Some(translucent::GatherMode::Vertex), ..Overrides::default() };
        let other = Overrides {
            max_error: Some(0.03),
            gather: Some(translucent::GatherMode::Hierarchical),
            ..Overrides::default()
        };
        let mut renderer = Renderer::new(gpu, PreparedScene::new(&scene, &first).unwrap()).unwrap();
        renderer.frame(&renderer.plan(Change::Everything)).unwrap();
        let before = renderer.image().unwrap();
        renderer.edit(SceneEdit::Scene(Box::new(PreparedScene::new(&scene, &other).unwrap()))).unwrap();
        assert_eq!(renderer.pending_change(), Some(Change::Everything));
        let counts = frame(gpu, &mut renderer);
        assert_eq!(counts.get("splat.comp"), 1, "{counts:?}");
        let edited = renderer.image().unwrap();
        drop(renderer);
        let fresh = run_all(gpu, PreparedScene::new(&scene, &other).unwrap()).image().unwrap();
        assert!(edited == fresh, "the edited renderer's image differs from a fresh one's");
        assert!(edited != before, "the other settings drew the same image");
    });
}

/// `Output::Display` is for a host's image (the viewer's swapchain); the renderer's own image is
/// tone-mapped by its own pass, so asking for it there is refused before anything is made.
#[test]
fn display_output_on_the_renderers_own_image_is_refused() {
    with_gpu(|gpu| {
        let options = translucent::RendererOptions {
            output: translucent::render::options::Output::Display,
            ..translucent::RendererOptions::default()
        };
        let scene = PreparedScene::new(&Scene::builtin(), &Overrides { samples: Some(400), ..Overrides::default() });
        let made = Renderer::with_options(gpu, scene.unwrap(), translucent::TargetDesc::Own, options);
        assert!(matches!(made, Err(translucent::RenderError::DisplayOnOwnTarget)), "{:?}", made.err());
    });
}

/// `model = "auto"` (the default) takes the transport kernel where the dipole's predicted error
/// against the light is over `render.max_error`, and the dipole where it is within: a 2 cm
/// marble sphere is predicted 20 to 24% off, so a 1% target walks the kernel and a 40% one does
/// not; a material edit chooses anew, and one that would need single scattering's tables is
/// refused.
#[test]
fn auto_takes_the_kernel_only_where_the_dipoles_predicted_error_is_over_the_target() {
    let text = std::fs::read_to_string(repo_path("assets/scenes/sphere-marble.toml")).unwrap();
    let at = |t: f64| prepare(&text, &Overrides { max_error: Some(t), ..Overrides::default() });
    let tight = at(0.01);
    assert!(tight.objects[0].wants_transport(), "{:?}", tight.objects[0].model);
    let loose = at(0.4);
    assert!(!loose.objects[0].wants_transport(), "{:?}", loose.objects[0].model);
    let dipole = text.replace("mm_per_unit = 1000.0", "mm_per_unit = 1000.0, model = \"dipole\"");
    let named = prepare(&dipole, &Overrides { max_error: Some(0.01), ..Overrides::default() });
    assert!(!named.objects[0].wants_transport(), "{:?}", named.objects[0].model);
    // A medium a thousand times denser in a sphere as large: its diffusion length is a thousandth,
    // near the half-space, where the dipole is within 40% and a 40% target keeps it.
    with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, loose).unwrap();
        let marble = Material::preset("marble").unwrap();
        let dense = Material {
            sigma_a: marble.sigma_a.map(|s| s * 1000.0),
            sigma_s_prime: marble.sigma_s_prime.map(|s| s * 1000.0),
            ..marble
        };
        renderer.edit(SceneEdit::Material { object: 0, material: dense }).unwrap();
        let choice = renderer.scene().objects[0].model.clone().unwrap();
        assert!(choice.channels.iter().all(|c| c.dipole.error < 0.05), "{choice}");
        // Ketchup's dark channels would take single scattering, whose tables were not built
        // with this scene: refused, the object unchanged.
        let ketchup = Material::preset("ketchup").unwrap();
        let refused = renderer.edit(SceneEdit::Material { object: 0, material: ketchup }).unwrap_err();
        assert!(refused.to_string().contains("single scattering between points"), "{refused}");
        assert_eq!(renderer.scene().objects[0].model.clone().unwrap(), choice);
    });
}

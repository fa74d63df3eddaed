//! The scene format: the built-in scene parses; mistakes name the key path and line.

use translucent::sampling::Method;
use translucent::scene::{GatherMode, Light, MaterialSpec, Scene, SceneError, Shape};

fn error_of(text: &str) -> String {
    match Scene::parse(text, "test.toml", None) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

const MINIMAL: &str = r#"
[camera]
eye = [0.0, 1.0, 3.0]
target = [0.0, 0.0, 0.0]

[[object]]
shape = { type = "sphere", radius = 1.0 }
material = { type = "translucent", preset = "skimmilk", mm_per_unit = 10.0 }

[[light]]
type = "point"
position = [2.0, 2.0, 2.0]
intensity = [1.0, 1.0, 1.0]
"#;

#[test]
fn builtin_scene_is_the_marble_bunny() {
    let scene = Scene::builtin();
    let s = &scene.file;
    assert!(matches!(&s.objects[0].shape, Shape::Mesh { path, .. } if path == "../bunny-37k.obj"));
    assert!(matches!(&s.objects[0].material, MaterialSpec::Translucent { preset: Some(p), .. } if p == "marble"));
    assert!(matches!(s.objects[1].material, MaterialSpec::Opaque { .. }));
    assert!(s.lights.iter().any(|l| matches!(l, Light::Environment { .. })));
    // Accurate by default: no count, the 1% error target chooses it.
    assert_eq!(s.sampling.count, None);
    assert_eq!(s.render.max_error, 0.01);
    assert!(scene.resolve("../bunny-37k.obj").is_ok());
    assert!(scene.resolve("missing.obj").is_err());
}

#[test]
fn the_built_in_scene_file_loads_from_disk_as_the_binary_embeds_it() {
    // assets/scenes/default.toml is both the embedded scene and a file a user can edit: its mesh
    // path must resolve from its own folder as well as among the embedded assets.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let scene = Scene::load(&path).unwrap();
    let Shape::Mesh { path: mesh, .. } = &scene.file.objects[0].shape else { panic!("the first object is the bunny") };
    match scene.resolve(mesh).unwrap() {
        translucent::scene::AssetSource::File(file) => assert!(file.is_file(), "{} is missing", file.display()),
        translucent::scene::AssetSource::Embedded(_) => panic!("a scene read from disk resolves from disk"),
    }
}

#[test]
fn defaults_fill_what_is_left_out() {
    let scene = Scene::parse(MINIMAL, "test.toml", None).unwrap();
    assert_eq!(scene.file.camera.resolution, [512, 512]);
    assert_eq!(scene.file.sampling.method, Method::Turk);
    assert_eq!(scene.file.render.gather, GatherMode::Vertex);
    assert_eq!(scene.file.render.gather_given, None);
    assert_eq!(scene.file.sampling.count, None);
}

#[test]
fn unknown_key_names_key_and_line() {
    let text = MINIMAL.replace("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 0.0]\nfov = 40.0");
    let e = error_of(&text);
    assert!(e.contains("test.toml") && e.contains("fov") && e.contains("line 5"), "{e}");
    let text = MINIMAL.replace("intensity = [1.0, 1.0, 1.0]", "intensity = [1.0, 1.0, 1.0]\ncolour = 2");
    let e = error_of(&text);
    assert!(e.contains("colour") && e.contains("line 14"), "{e}");
}

#[test]
fn bad_values_name_the_key() {
    for (from, to, key) in [
        ("eye = [0.0, 1.0, 3.0]", "eye = [0.0, 0.0, 0.0]", "camera.target"),
        ("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 0.0]\nfov_y = 190.0", "camera.fov_y"),
        ("radius = 1.0", "radius = -1.0", "object[0].shape"),
        ("mm_per_unit = 10.0", "mm_per_unit = nan", "object[0].material.mm_per_unit"),
        ("intensity = [1.0, 1.0, 1.0]", "intensity = [1.0, -1.0, 1.0]", "light[0].intensity"),
        ("type = \"point\"", "type = \"laser\"", "light[0]"),
        ("preset = \"skimmilk\", ", "", "object[0].material"),
        ("eye = [0.0, 1.0, 3.0]", "eye = [0.0, 3.0, 0.0]", "camera.up"),
        ("mm_per_unit = 10.0", "mm_per_unit = 10.0, roughness = 2.0", "object[0].material.roughness"),
    ] {
        let text = MINIMAL.replace(from, to);
        assert_ne!(text, MINIMAL, "replacement {from:?} did not apply");
        let e = error_of(&text);
        assert!(e.contains(key), "expected {key} in: {e}");
    }
    let e = error_of(&format!("{MINIMAL}\n[sampling]\nmethod = \"grid\"\n"));
    assert!(e.contains("sampling.method") && e.contains("line 16"), "{e}");
}

#[test]
fn a_fixed_size_array_of_the_wrong_length_is_refused_naming_file_line_and_key() {
    let with_camera = |line: &str| MINIMAL.replace("target = [0.0, 0.0, 0.0]", &format!("target = [0.0, 0.0, 0.0]\n{line}"));
    for (text, key, line) in [
        (with_camera("resolution = [32, 32, 32]"), "camera.resolution", "line 5"),
        (with_camera("resolution = [32]"), "camera.resolution", "line 5"),
        (MINIMAL.replace("eye = [0.0, 1.0, 3.0]", "eye = [0.0, 1.0, 3.0, 4.0]"), "camera.eye", "line 3"),
        (MINIMAL.replace("intensity = [1.0, 1.0, 1.0]", "intensity = [1.0, 1.0]"), "light[0]", "line 10"),
        (
            MINIMAL.replace("preset = \"skimmilk\"", "sigma_a = [0.1, 0.1, 0.1, 0.1], sigma_s_prime = [1.0, 1.0, 1.0]"),
            "object[0].material",
            "line 8",
        ),
    ] {
        let e = error_of(&text);
        assert!(e.contains("test.toml") && e.contains(key) && e.contains(line), "expected {key}, {line} in: {e}");
        assert!(e.contains("invalid length"), "{e}");
    }
}

#[test]
fn syntax_error_names_the_line() {
    let e = error_of("[camera]\neye = [0.0, 1.0\n");
    assert!(e.contains("line 2"), "{e}");
}

#[test]
fn missing_file_names_the_path() {
    let e = Scene::load(std::path::Path::new("/no/such/scene.toml")).unwrap_err();
    assert!(matches!(e, SceneError::Read { .. }));
    assert!(e.to_string().contains("/no/such/scene.toml"), "{e}");
}

// Regression tests for what fuzzing (fuzz/, scripts/fuzz) and its finiteness checks found.

use translucent::scene::build::{Overrides, PreparedScene};
use translucent::scene::lights::{Environment, EnvironmentError, LightKind};

/// A Radiance .hdr of `width` x `height` texels (flat RGBE scanlines, no run-length encoding),
/// every texel the same RGBE bytes.
fn radiance_hdr(width: usize, height: usize, rgbe: [u8; 4]) -> Vec<u8> {
    let mut bytes = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
    for _ in 0..width * height {
        bytes.extend_from_slice(&rgbe);
    }
    bytes
}

/// Prepare `text` (built-in shapes only), asserting everything handed to the GPU is finite.
fn prepare_finite(text: &str) -> PreparedScene {
    let scene = Scene::parse(text, "test.toml", None).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert!(scene.file.camera.view().is_finite(), "view matrix");
    let prepared = PreparedScene::new(&scene, &Overrides::default()).unwrap_or_else(|e| panic!("{e:#}"));
    let (centre, radius) = prepared.bounds;
    assert!(scene.file.camera.projection(centre, radius).is_finite(), "projection");
    for l in &prepared.lights {
        let finite = match l.kind {
            LightKind::Directional { direction, irradiance } => direction.is_finite() && irradiance.is_finite(),
            LightKind::Point { position, intensity } => position.is_finite() && intensity.is_finite(),
            LightKind::Spot { position, axis, intensity, .. } => {
                position.is_finite() && axis.is_finite() && intensity.is_finite()
            }
        };
        assert!(finite && l.shadow_matrix.is_finite(), "light[{}]: {:?} {}", l.source, l.kind, l.shadow_matrix);
    }
    prepared
}

fn prepare_error(text: &str) -> String {
    let scene = Scene::parse(text, "test.toml", None).unwrap_or_else(|e| panic!("{e}\n{text}"));
    match PreparedScene::new(&scene, &Overrides::default()) {
        Ok(_) => panic!("expected an error preparing:\n{text}"),
        Err(e) => format!("{e:#}"),
    }
}

#[test]
fn environment_map_texels_that_overflow_the_median_cut_are_refused() {
    // Found by the `environment` fuzz target: RGBE exponent 255 decodes to ~1.7e38, finite, but
    // the median cut summed it to an infinite light with a NaN direction.
    let e = Environment::from_bytes(&radiance_hdr(2, 2, [0, 0x27, 0xff, 0xff]), "bright.hdr").unwrap_err();
    assert!(matches!(e, EnvironmentError::TooBright { x: 0, y: 0, .. }), "{e:?}");
    let message = e.to_string();
    assert!(message.contains("bright.hdr") && message.contains("(0, 0)") && message.contains("1e30"), "{message}");

    // An ordinary map decodes from memory and gives finite lights.
    let env = Environment::from_bytes(&radiance_hdr(4, 2, [128, 128, 128, 129]), "ok.hdr").unwrap();
    assert_eq!((env.width, env.height), (4, 2));
    assert!(env.median_cut(4).iter().all(|(d, e)| d.is_finite() && e.is_finite()));
}

#[test]
fn tiny_camera_up_and_light_directions_stay_finite() {
    // Non-zero vectors whose squared length underflows f32 passed the checks and normalised
    // to NaN: a NaN view matrix, NaN directional and spot lights.
    let text =
        MINIMAL.replace("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 0.0]\nup = [1e-30, 1e-30, 0.0]").replace(
            "type = \"point\"\nposition = [2.0, 2.0, 2.0]",
            "type = \"spot\"\nangle = 30.0\ndirection = [-1e-30, -1e-30, -1e-30]\nposition = [2.0, 2.0, 2.0]",
        ) + "\n[[light]]\ntype = \"directional\"\ndirection = [1e-30, 1e-30, 0.0]\nirradiance = [1.0, 1.0, 1.0]\n";
    let text = text.replace("radius = 1.0", "radius = 1.0, divisions = 8") + "\n[sampling]\ncount = 16\n";
    prepare_finite(&text);
}

#[test]
fn point_light_at_the_centre_of_the_casters_has_a_finite_shadow_frustum() {
    // A point light exactly at the casters' centre looked along a zero vector: NaN shadow matrix.
    let text = MINIMAL
        .replace("position = [2.0, 2.0, 2.0]", "position = [0.0, 0.0, 0.0]")
        .replace("radius = 1.0", "radius = 1.0, divisions = 8")
        + "\n[sampling]\ncount = 16\n";
    prepare_finite(&text);
}

#[test]
fn camera_limits_name_the_key_and_the_limit() {
    for (from, to, key, limit) in [
        // A field of view that underflows to 0 radians gave an infinite projection.
        ("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 0.0]\nfov_y = 1e-45", "camera.fov_y", "0.001"),
        // An eye 1e-30 from the target: the view direction's length underflowed, NaN view.
        ("eye = [0.0, 1.0, 3.0]", "eye = [0.0, 1e-30, 0.0]", "camera.target", "1e-18"),
        // 4e19 away was reported as "up is parallel to the view direction".
        ("eye = [0.0, 1.0, 3.0]", "eye = [0.0, 4e19, 1.0]", "camera.eye", "1e18"),
        ("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, -3e38]", "camera.target", "1e18"),
    ] {
        let text = MINIMAL.replace(from, to);
        assert_ne!(text, MINIMAL, "replacement {from:?} did not apply");
        let e = error_of(&text);
        assert!(e.contains(key) && e.contains(limit), "expected {key} and {limit} in: {e}");
    }
    // Inside the limits the camera is finite.
    let text = MINIMAL.replace("eye = [0.0, 1.0, 3.0]", "eye = [0.0, 0.0, 1e-17]");
    assert!(Scene::parse(&text, "test.toml", None).unwrap().file.camera.view().is_finite());
}

#[test]
fn positions_beyond_the_coordinate_limit_name_the_key() {
    // A point light 3e38 away had an infinite distance to the casters: NaN shadow matrix.
    let text = MINIMAL.replace("position = [2.0, 2.0, 2.0]", "position = [3e38, 0.0, 0.0]");
    let e = error_of(&text);
    assert!(e.contains("light[0].position") && e.contains("1e18") && e.contains("line 12"), "{e}");
    let text = MINIMAL.replace("radius = 1.0 }", "radius = 1.0 }\ntransform = { translate = [0.0, -2e18, 0.0] }");
    let e = error_of(&text);
    assert!(e.contains("object[0].transform.translate") && e.contains("1e18"), "{e}");
}

#[test]
fn objects_placed_beyond_the_coordinate_limit_are_refused_before_the_gpu() {
    // A sphere of radius 3e38 (finite vertices) had an infinite bounding sphere: infinite
    // projection and shadow matrices.
    for shape in ["radius = 3e38, divisions = 8", "radius = 1e10, divisions = 8 }\ntransform = { scale = 1e10"] {
        let text = MINIMAL.replace("radius = 1.0", shape);
        // Refused when parsed (a shape's size is at most 1e9) or when prepared (a mesh's vertices
        // within 1e9 of the origin, every object within 1e18), naming the object and the limit.
        let e = match Scene::parse(&text, "test.toml", None) {
            Err(e) => e.to_string(),
            Ok(_) => prepare_error(&text),
        };
        assert!(e.contains("object[0]") && (e.contains("1e9") || e.contains("1e18")), "{e}");
    }
}

#[test]
fn an_environment_scale_that_overflows_its_lights_names_the_key() {
    let dir = std::env::temp_dir().join(format!("translucent-scene-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Texels of 4e29 (RGBE exponent 128 + 99), under the loader's 1e30 limit.
    std::fs::write(dir.join("sky.hdr"), radiance_hdr(4, 2, [128, 128, 128, 227])).unwrap();
    let text = MINIMAL.replace("radius = 1.0", "radius = 1.0, divisions = 8")
        + "\n[[light]]\ntype = \"environment\"\nmap = \"sky.hdr\"\nscale = 1e10\ndirections = 4\n\n[sampling]\ncount = 16\n";
    let scene = Scene::parse(&text, "test.toml", Some(dir.clone())).unwrap();
    let e = format!("{:#}", PreparedScene::new(&scene, &Overrides::default()).unwrap_err());
    assert!(e.contains("light[1].scale") && e.contains("not finite"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_chosen_gathers_epsilon_follows_the_error_target() {
    use translucent::scene::{ACCURATE_GATHER_EPSILON, DEFAULT_MAX_ERROR, accurate_gather_epsilon};
    assert_eq!(accurate_gather_epsilon(DEFAULT_MAX_ERROR), ACCURATE_GATHER_EPSILON);
    // Tighter targets cluster less; loose ones are capped.
    assert!(accurate_gather_epsilon(0.003) < accurate_gather_epsilon(0.01));
    assert!(accurate_gather_epsilon(0.5) <= 2.0);
    // A scene that names no gather and no epsilon gets the one its target asks for.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/sphere-ketchup.toml");
    let scene = Scene::load(&path).unwrap();
    let overrides = translucent::scene::build::Overrides { max_error: Some(0.003), ..Default::default() };
    let prepared = translucent::scene::build::PreparedScene::new(&scene, &overrides).unwrap();
    let render = &prepared.scene.file.render;
    assert_eq!(render.gather, GatherMode::Hierarchical, "ketchup at 0.3% places over 1,600 samples");
    assert_eq!(render.gather_epsilon, accurate_gather_epsilon(0.003));
}

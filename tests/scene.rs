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
    assert!(matches!(&s.objects[0].shape, Shape::Mesh { path } if path == "bunny-37k.obj"));
    assert!(matches!(&s.objects[0].material, MaterialSpec::Translucent { preset: Some(p), .. } if p == "marble"));
    assert!(matches!(s.objects[1].material, MaterialSpec::Opaque { .. }));
    assert!(s.lights.iter().any(|l| matches!(l, Light::Environment { .. })));
    assert_eq!(s.sampling.count, 400);
    assert!(scene.resolve("bunny-37k.obj").is_ok());
    assert!(scene.resolve("missing.obj").is_err());
}

#[test]
fn defaults_fill_what_is_left_out() {
    let scene = Scene::parse(MINIMAL, "test.toml", None).unwrap();
    assert_eq!(scene.file.camera.resolution, [512, 512]);
    assert_eq!(scene.file.sampling.method, Method::Turk);
    assert_eq!(scene.file.render.gather, GatherMode::Vertex);
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

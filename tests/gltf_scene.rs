//! glTF 2.0 scenes (issue 48, part 3): a `.gltf` / `.glb` read as a whole scene renders as the
//! TOML scene stating the same camera, lights and material; each mapping (camera, each light
//! type, the volume material, the overrides) gives the scene values docs/SCENES.md documents;
//! and bad files are refused naming the part of the file.
#![cfg(feature = "gltf")]

mod common;

use common::{repo_path, temp_dir, text, translucent};
use serde_json::{Value, json};
use std::path::PathBuf;
use translucent::mesh::glb_bytes;
use translucent::optics::albedo::reduced_albedo;
use translucent::scene::{
    BadValue, GltfOverrides, GltfPart, GltfSceneProblem, Light, MaterialSpec, Scene, SceneError, SceneFile,
};

/// A `.glb` of one triangle (node 0, mesh 0, its primitive of material 0 where `extra` has
/// materials) with `extra`'s top-level keys added; `extra`'s `nodes` come after node 0, and its
/// `scenes` replace the one scene of node 0 and them all.
fn glb(extra: Value) -> Vec<u8> {
    let positions = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    bin.extend([0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    let mut primitive = json!({"attributes": {"POSITION": 0}, "indices": 1});
    if extra.get("materials").is_some() {
        primitive["material"] = json!(0);
    }
    let mut nodes = vec![json!({"name": "triangle", "mesh": 0})];
    nodes.extend(extra.get("nodes").and_then(Value::as_array).cloned().unwrap_or_default());
    let mut root = json!({
        "asset": {"version": "2.0"}, "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "meshes": [{"primitives": [primitive]}],
        "buffers": [{"byteLength": 48}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}
        ],
    });
    for (key, value) in extra.as_object().expect("an object") {
        root[key] = value.clone();
    }
    root["nodes"] = Value::Array(nodes);
    glb_bytes(&serde_json::to_vec(&root).unwrap(), &bin)
}

fn scene_of(extra: Value, overrides: &GltfOverrides) -> Result<SceneFile, SceneError> {
    Scene::from_gltf_slice(&glb(extra), "test.glb", (PathBuf::from("."), "test.glb"), overrides).map(|s| s.file)
}

fn problem<T: std::fmt::Debug>(result: Result<T, SceneError>) -> (String, GltfSceneProblem) {
    match result {
        Err(e @ SceneError::Gltf { .. }) => {
            let message = e.to_string();
            let SceneError::Gltf { problem, .. } = e else { unreachable!() };
            (message, *problem)
        }
        other => panic!("not a glTF scene error: {other:?}"),
    }
}

fn close(a: [f32; 3], b: [f32; 3]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-6 * (1.0 + y.abs()))
}

/// The asset's material as the documented mapping gives it: per channel `sigma_t' =
/// -ln(attenuationColor) / attenuationDistance` per metre, over 1000 per millimetre, split by
/// the reduced albedo whose dipole reflects the base colour; eta the file's ior.
fn stone() -> ([f64; 3], [f64; 3], f64) {
    let (color, distance, base) = ([0.112f32, 0.0728, 0.0498], 0.001f32, [0.83f32, 0.79, 0.75]);
    let eta = f64::from(1.3f32);
    let (mut sigma_a, mut sigma_s) = ([0.0; 3], [0.0; 3]);
    for c in 0..3 {
        let sigma_t = -f64::from(color[c]).ln() / f64::from(distance) / 1000.0;
        let alpha = reduced_albedo(f64::from(base[c]), eta).unwrap();
        sigma_s[c] = alpha * sigma_t;
        sigma_a[c] = (1.0 - alpha) * sigma_t;
    }
    (sigma_a, sigma_s, eta)
}

/// The asset, `assets/scenes/bunny-volume.glb` (examples/gltf_scene.rs), renders byte for byte
/// as a TOML scene stating its camera, lights and material, taking the bunny from the same file
/// by its node's name.
#[test]
fn a_gltf_scene_renders_the_same_image_as_its_toml_twin() {
    let dir = temp_dir("gltf-scene-twin");
    let asset = repo_path("assets/scenes/bunny-volume.glb");
    let (sigma_a, sigma_s, eta) = stone();
    let twin = format!(
        r#"[camera]
eye = [0.0, 0.0234375, 0.15625]
target = [0.0, 0.0234375, -0.84375]
fov_y = 30.0

[[object]]
shape = {{ type = "mesh", path = {path:?}, node = "bunny" }}
material = {{ type = "translucent", sigma_a = {sigma_a:?}, sigma_s_prime = {sigma_s:?}, eta = {eta:?}, mm_per_unit = 1000.0, roughness = 0.35 }}

[[light]]
type = "point"
position = [0.03125, 0.0625, -0.0625]
intensity = [0.015625, 0.013671875, 0.01171875]

[[light]]
type = "directional"
direction = [0.0, 0.0, 1.0]
irradiance = [0.5, 0.5, 0.5]
"#,
        path = asset.to_str().unwrap()
    );
    let toml = dir.join("twin.toml");
    std::fs::write(&toml, twin).unwrap();
    let mut pngs = Vec::new();
    for (name, scene) in [("gltf", asset.as_path()), ("toml", toml.as_path())] {
        let png = dir.join(format!("{name}.png"));
        let args = ["render", scene.to_str().unwrap(), "--resolution", "96x96", "--samples", "1500"];
        let out = translucent(&[&args[..], &["-o", png.to_str().unwrap()]].concat(), &[]);
        assert!(out.status.success(), "{name}: {}", text(&out.stderr));
        pngs.push(std::fs::read(&png).unwrap());
    }
    assert!(pngs[0] == pngs[1], "the glTF scene and its TOML twin render differently");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The asset's camera node (a translation) and its perspective camera: eye at the node, looking
/// down -z, 30 degrees; a square image without an aspect ratio.
#[test]
fn the_camera_is_the_first_camera_node_looking_down_its_minus_z() {
    let scene = Scene::load(&repo_path("assets/scenes/bunny-volume.glb")).unwrap();
    let c = &scene.file.camera;
    assert_eq!((c.eye, c.target, c.up), ([0.0, 0.0234375, 0.15625], [0.0, 0.0234375, -0.84375], [0.0, 1.0, 0.0]));
    assert_eq!((c.fov_y, c.resolution), (30.0, [512, 512]));
    assert_eq!(scene.file.objects.len(), 1);
}

/// A camera node turned 90 degrees about y under a translated parent: the eye where both place
/// it, looking down the turned -z (world -x), its +y up; the aspect ratio sets the width.
#[test]
fn a_turned_camera_node_under_a_parent_looks_down_its_turned_minus_z() {
    let half = std::f32::consts::FRAC_1_SQRT_2;
    let file = scene_of(
        json!({
            "nodes": [
                {"translation": [1.0, 2.0, 3.0], "children": [2]},
                {"rotation": [0.0, half, 0.0, half], "translation": [0.0, 0.0, 1.0], "camera": 0}
            ],
            "scenes": [{"nodes": [0, 1]}],
            "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "aspectRatio": 2.0, "znear": 0.1}}]
        }),
        &GltfOverrides::default(),
    )
    .unwrap();
    let c = &file.camera;
    assert!(close(c.eye, [1.0, 2.0, 4.0]), "{:?}", c.eye);
    assert!(close(c.target, [0.0, 2.0, 4.0]), "{:?}", c.target);
    assert!(close(c.up, [0.0, 1.0, 0.0]), "{:?}", c.up);
    assert_eq!(c.resolution, [1024, 512]);
    assert!((c.fov_y - 0.5f32.to_degrees()).abs() < 1e-4);
}

/// No camera and no light: a camera looking at the meshes' centre from the front, the whole
/// bounding sphere in view, and the built-in scene's key light and sky.
#[test]
fn a_file_without_camera_or_lights_is_framed_and_lit_by_default() {
    let file = scene_of(json!({}), &GltfOverrides::default()).unwrap();
    let c = &file.camera;
    assert_eq!(c.target, [0.5, 0.5, 0.0]);
    let distance = glam::Vec3::from(c.eye).distance(glam::Vec3::from(c.target));
    let radius = 0.5 * 2f32.sqrt();
    assert!(radius / distance < (0.5 * c.fov_y.to_radians()).sin(), "{distance}");
    assert!(c.eye[2] > 0.0 && c.eye[1] > c.target[1], "{:?}", c.eye);
    assert!(matches!(file.lights[..], [Light::Directional { .. }, Light::Environment { .. }]));
}

/// `KHR_lights_punctual`: lux and candela over 683 lm/W times the colour; a directional light
/// towards its node's +z, a point at its node, a spot down its node's -z with `angle` the outer
/// cone in degrees and `softness` 1 - inner/outer.
#[test]
fn each_punctual_light_becomes_its_scene_light_in_watts() {
    let half = std::f32::consts::FRAC_1_SQRT_2;
    let lights = json!({"KHR_lights_punctual": {"lights": [
        {"type": "directional", "color": [1.0, 0.5, 0.25], "intensity": 1366.0},
        {"type": "point", "intensity": 68.3},
        {"type": "spot", "intensity": 6.83, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}
    ]}});
    let file = scene_of(
        json!({
            "extensionsUsed": ["KHR_lights_punctual"], "extensions": lights,
            "nodes": [
                {"rotation": [-half, 0.0, 0.0, half], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                {"translation": [0.0, 1.0, 2.0], "extensions": {"KHR_lights_punctual": {"light": 1}}},
                {"translation": [3.0, 0.0, 0.0], "rotation": [0.0, half, 0.0, half],
                 "extensions": {"KHR_lights_punctual": {"light": 2}}}
            ]
        }),
        &GltfOverrides::default(),
    )
    .unwrap();
    let [
        Light::Directional { direction, irradiance, .. },
        Light::Point { position, intensity, .. },
        Light::Spot { position: at, direction: axis, intensity: spot, angle, softness, .. },
    ] = &file.lights[..]
    else {
        panic!("{:?}", file.lights)
    };
    // Turned -90 degrees about x, the node's +z points to world +y: light from above.
    assert!(close(*direction, [0.0, 1.0, 0.0]), "{direction:?}");
    assert!(close(*irradiance, [2.0, 1.0, 0.5]), "{irradiance:?}");
    assert_eq!((*position, *intensity), ([0.0, 1.0, 2.0], [0.1; 3]));
    assert!(close(*at, [3.0, 0.0, 0.0]) && close(*axis, [-1.0, 0.0, 0.0]), "{at:?} {axis:?}");
    assert!(close(*spot, [0.01; 3]), "{spot:?}");
    assert!((angle - 0.5f32.to_degrees()).abs() < 1e-4 && (softness - 0.6).abs() < 1e-6, "{angle} {softness}");
}

/// `KHR_materials_volume`: the asset's material is the medium the documented mapping gives, and
/// its dipole reflects the base colour; a thin-walled volume (thickness 0) and a plain material
/// are opaque in their base colour; diffuse transmission with a volume is translucent.
#[test]
fn a_volume_material_becomes_the_medium_its_attenuation_and_colour_give() {
    let scene = Scene::load(&repo_path("assets/scenes/bunny-volume.glb")).unwrap();
    let MaterialSpec::Translucent { sigma_a: Some(a), sigma_s_prime: Some(s), eta: Some(eta), mm_per_unit, .. } =
        scene.file.objects[0].material
    else {
        panic!("{:?}", scene.file.objects[0].material)
    };
    assert_eq!((a, s, eta, mm_per_unit), (stone().0, stone().1, stone().2, 1000.0));
    let material = translucent::optics::Material::new("stone", a, s, eta).unwrap();
    for (c, d) in material.dipoles(1000.0).unwrap().iter().enumerate() {
        assert!((d.r_d_total() - f64::from([0.83f32, 0.79, 0.75][c])).abs() < 1e-9);
        assert!((d.sigma_t_prime / 1e6 + f64::from([0.112f32, 0.0728, 0.0498][c]).ln() / 1e3).abs() < 1e-9);
    }
    let with = |extensions: Value| {
        let material = json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.4, 0.3, 1.0], "roughnessFactor": 0.6},
            "extensions": extensions});
        scene_of(json!({"materials": [material]}), &GltfOverrides::default()).map(|f| f.objects[0].material.clone())
    };
    let volume = json!({"thicknessFactor": 0.0, "attenuationDistance": 0.01, "attenuationColor": [0.5, 0.5, 0.5]});
    for extensions in [json!({"KHR_materials_volume": volume}), json!({})] {
        let spec = with(extensions).unwrap();
        assert!(matches!(spec, MaterialSpec::Opaque { albedo: [0.5, 0.4, 0.3], roughness: 0.6 }), "{spec:?}");
    }
    let volume = json!({"thicknessFactor": 0.1, "attenuationDistance": 0.01, "attenuationColor": [0.5, 0.5, 0.5]});
    let both = json!({"KHR_materials_volume": volume, "KHR_materials_diffuse_transmission": {}});
    assert!(matches!(with(both).unwrap(), MaterialSpec::Translucent { .. }));
    let (message, p) = problem(with(json!({"KHR_materials_diffuse_transmission": {}})));
    assert!(matches!(p, GltfSceneProblem::NoVolume { .. }), "{message}");
}

/// The overrides beside a glTF scene replace a material by its name and set `[sampling]` and
/// `[render]`; a name no material has, or a key the format has not, is refused.
#[test]
fn the_overrides_replace_a_material_by_name_and_set_sampling() {
    let dir = temp_dir("gltf-scene-overrides");
    let glb_path = dir.join("bunny.glb");
    std::fs::copy(repo_path("assets/scenes/bunny-volume.glb"), &glb_path).unwrap();
    let sidecar = GltfOverrides::path_beside(&glb_path);
    assert_eq!(sidecar, dir.join("bunny.glb.toml"));
    let overrides = r#"
[material.stone]
type = "translucent"
preset = "marble"
mm_per_unit = 1000.0

[sampling]
count = 700

[render]
exposure = 2.0
"#;
    std::fs::write(&sidecar, overrides).unwrap();
    let scene = Scene::load(&glb_path).unwrap();
    assert!(
        matches!(&scene.file.objects[0].material, MaterialSpec::Translucent { preset: Some(p), .. } if p == "marble")
    );
    assert_eq!((scene.file.sampling.count, scene.file.render.exposure), (Some(700), 2.0));

    std::fs::write(&sidecar, overrides.replace("material.stone", "material.marble")).unwrap();
    let e = Scene::load(&glb_path).unwrap_err();
    let SceneError::Gltf { problem, .. } = &e else { panic!("{e:?}") };
    assert!(
        matches!(&**problem, GltfSceneProblem::NoSuchMaterial { name, names } if name == "marble" && names == &["stone"])
    );

    std::fs::write(&sidecar, overrides.replace("count = 700", "cuont = 700")).unwrap();
    let message = Scene::load(&glb_path).unwrap_err().to_string();
    assert!(message.starts_with(&format!("{}: line 8: at key `sampling.cuont`", sidecar.display())), "{message}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad parts are refused naming them: an orthographic camera, a spot cone the scene cannot
/// take, an albedo over 1, a volume without attenuation; a file placing no mesh.
#[test]
fn bad_gltf_scenes_are_refused_naming_the_part() {
    let camera = json!({"nodes": [{"camera": 0}], "cameras": [{"type": "orthographic", "orthographic":
        {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}}]});
    let (message, p) = problem(scene_of(camera, &GltfOverrides::default()));
    assert!(matches!(p, GltfSceneProblem::Orthographic { camera: GltfPart::Camera { node: 1, camera: 0 } }));
    assert_eq!(message, "test.glb: camera 0 (node 1) is orthographic; only perspective cameras are read");

    let spot = json!({"extensionsUsed": ["KHR_lights_punctual"], "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "wide", "type": "spot", "intensity": 1.0, "spot": {"outerConeAngle": 1.5707964}}]}},
        "nodes": [{"extensions": {"KHR_lights_punctual": {"light": 0}}}]});
    let (message, p) = problem(scene_of(spot, &GltfOverrides::default()));
    assert!(
        matches!(&p, GltfSceneProblem::Value { part: GltfPart::Light { index: 0, node: 1, .. }, key, .. } if key == "angle"),
        "{p:?}"
    );
    assert!(message.starts_with("test.glb: KHR_lights_punctual light 0 \"wide\" (node 1): `angle`: "), "{message}");

    let bright =
        json!({"materials": [{"name": "glow", "pbrMetallicRoughness": {"baseColorFactor": [1.5, 1.0, 1.0, 1.0]}}]});
    let (message, p) = problem(scene_of(bright, &GltfOverrides::default()));
    let GltfSceneProblem::Value { part, key, value } = p else { panic!("{message}") };
    assert_eq!(part, GltfPart::Material { index: Some(0), name: Some("glow".into()) });
    assert_eq!((key.as_str(), &value), ("material.albedo", &BadValue::AlbedoAboveOne([1.5, 1.0, 1.0])));

    let clear =
        json!({"materials": [{"name": "glass", "extensions": {"KHR_materials_volume": {"thicknessFactor": 1.0}}}]});
    let (message, p) = problem(scene_of(clear, &GltfOverrides::default()));
    assert!(matches!(p, GltfSceneProblem::NoExtinction { channel: 0, .. }), "{message}");
    assert!(message.contains("material 0 \"glass\""), "{message}");

    let empty = glb_bytes(br#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{}]}"#, &[]);
    let e = Scene::from_gltf_slice(&empty, "empty.glb", (PathBuf::from("."), "empty.glb"), &GltfOverrides::default());
    assert_eq!(e.unwrap_err().to_string(), "empty.glb: no scene places a mesh");
}

/// On the command line a bad glTF scene exits non-zero naming the file and the light, and
/// writes nothing; `plan` reads a good one.
#[test]
fn the_command_line_refuses_a_bad_gltf_scene_and_plans_a_good_one() {
    let dir = temp_dir("gltf-scene-cli");
    let bad = dir.join("bad.glb");
    let light = json!({"extensionsUsed": ["KHR_lights_punctual"], "extensions": {"KHR_lights_punctual": {"lights": [
        {"type": "point", "intensity": -1.0}]}}, "nodes": [{"extensions": {"KHR_lights_punctual": {"light": 0}}}]});
    std::fs::write(&bad, glb(light)).unwrap();
    let png = dir.join("out.png");
    let out = translucent(&["render", bad.to_str().unwrap(), "-o", png.to_str().unwrap()], &[]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success() && !png.exists(), "{stderr}");
    assert!(stderr.contains("bad.glb: KHR_lights_punctual light 0 (node 1): `intensity`"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");

    let asset = repo_path("assets/scenes/bunny-volume.glb");
    let out = translucent(&["plan", asset.to_str().unwrap(), "--samples", "500"], &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

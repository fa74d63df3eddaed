//! Helpers shared by the integration tests: paths in the repository, fresh temporary folders, the
//! `translucent` binary, a grid mesh, and a validated GPU context on lavapipe (or whatever
//! TRANSLUCENT_DEVICE names) that fails the test on any validation message, leaks at device
//! destruction included.
#![allow(dead_code)]

pub mod host;

use glam::{Mat4, Vec3};
use std::path::PathBuf;
use std::process::{Command, Output};
use std::sync::Arc;
use translucent::gpu::{Gpu, GpuOptions};
use translucent::mesh::{LoadOptions, Mesh};
use translucent::optics::kernel;
use translucent::render::plan::{Change, Pass};
use translucent::render::records::SplatRecord;
use translucent::render::renderer::Renderer;
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene, ResolvedMaterial};

// ---------------------------------------------------------------------------------------------
// Files

/// A `.glb` of one triangle: `positions`, one more per-vertex attribute `name` of glTF type
/// `kind` (`"VEC2"` or `"VEC3"`, `values` its floats, vertex by vertex), indices 0, 1, 2, placed
/// by the node JSON `node` (e.g. `{"mesh": 0}`). The buffer views' offsets are computed here.
pub fn triangle_glb(
    positions: [[f32; 3]; 3],
    name: &str,
    kind: &str,
    values: &[f32],
    node: serde_json::Value,
) -> Vec<u8> {
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let extra = bin.len();
    bin.extend(values.iter().flat_map(|x| x.to_le_bytes()));
    let indices = bin.len();
    bin.extend([0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    let (lo, hi) = positions.iter().fold(([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]), |(lo, hi), p| {
        (std::array::from_fn(|i| lo[i].min(p[i])), std::array::from_fn(|i| hi[i].max(p[i])))
    });
    let json = serde_json::json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [node],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, name: 1}, "indices": 2}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": extra},
            {"buffer": 0, "byteOffset": extra, "byteLength": indices - extra},
            {"buffer": 0, "byteOffset": indices, "byteLength": bin.len() - indices}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": kind},
            {"bufferView": 2, "componentType": 5125, "count": 3, "type": "SCALAR"}
        ]
    });
    translucent::mesh::glb_bytes(json.to_string().as_bytes(), &bin)
}

/// A path relative to the repository root.
pub fn repo_path(relative: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// A file in `assets/`.
pub fn asset(name: &str) -> PathBuf {
    repo_path("assets").join(name)
}

/// A mesh from `assets/`, loaded with the default options.
pub fn load_asset(name: &str) -> Mesh {
    Mesh::load(asset(name), &LoadOptions::default()).unwrap()
}

/// A fresh, empty folder under the system temp dir, for one test (`name` must be unique within
/// the test file; the process id keeps test files apart).
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("translucent-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

// ---------------------------------------------------------------------------------------------
// The binary

/// Run the `translucent` binary with `args` and extra environment variables, validation on and
/// the device left to its default choice.
pub fn translucent(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_translucent"));
    cmd.args(args).env("TRANSLUCENT_VALIDATION", "1").env_remove("TRANSLUCENT_DEVICE");
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("run translucent")
}

/// Run `translucent SUBCOMMAND ARGS...`.
pub fn subcommand(subcommand: &str, args: &[&str]) -> Output {
    translucent(&[&[subcommand], args].concat(), &[])
}

/// Captured output as text.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

// ---------------------------------------------------------------------------------------------
// Meshes

/// A flat n x n grid of vertices in the unit square of the xy plane, interior vertices jittered
/// in-plane by up to `jitter` of the spacing (a fixed sequence), then placed by `m`.
pub fn grid(n: usize, jitter: f64, m: Mat4) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::new();
    let mut state = 12345u64;
    let mut rnd = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let h = 1.0 / (n - 1) as f64;
    for i in 0..n {
        for j in 0..n {
            let interior = i > 0 && j > 0 && i < n - 1 && j < n - 1;
            let (dx, dy) = if interior { (rnd() * jitter * h, rnd() * jitter * h) } else { (0.0, 0.0) };
            let p = Vec3::new((i as f64 * h + dx) as f32, (j as f64 * h + dy) as f32, 0.0);
            pos.push(m.transform_point3(p));
        }
    }
    let id = |i: usize, j: usize| (i * n + j) as u32;
    let mut tris = Vec::new();
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (pos, tris)
}

// ---------------------------------------------------------------------------------------------
// The GPU

/// Options for a validated device: TRANSLUCENT_DEVICE if set, else the default choice.
pub fn validated_options() -> GpuOptions {
    GpuOptions { device: std::env::var("TRANSLUCENT_DEVICE").ok(), validation: true, ..GpuOptions::default() }
}

/// Run `f` with a fresh validated `Gpu`; after it returns, destroy the device and assert that
/// the validation layer said nothing. `f` must not keep clones of the `Arc<Gpu>`.
pub fn with_gpu<R>(f: impl FnOnce(&Arc<Gpu>) -> R) -> R {
    let gpu = Gpu::new(&validated_options()).unwrap_or_else(|e| {
        panic!(
            "GPU tests need a Vulkan device with validation layers: {e}\n\
             run `bash scripts/setup` (installs mesa-vulkan-drivers and vulkan-validationlayers)"
        )
    });
    let counters = gpu.validation();
    let result = f(&gpu);
    assert_eq!(Arc::strong_count(&gpu), 1, "a GPU resource outlived the test body");
    drop(gpu);
    assert_eq!(
        counters.total(),
        0,
        "Vulkan validation reported {} warnings and {} errors:\n{}",
        counters.warnings(),
        counters.errors(),
        counters.messages().join("\n")
    );
    result
}

// ---------------------------------------------------------------------------------------------
// Scenes and frames

/// A large translucent plane (size in mm, with 1 unit = 1 mm) under light from straight above,
/// in the dipole in every channel (the tests on it measure the dipole's sum; `"auto"` would give
/// a dark preset's channels single scattering between points).
pub fn plane_scene(preset: &str, size: f32, samples: usize, extra: &str) -> String {
    format!(
        r#"
[camera]
eye = [0.0, {h}, {z}]
target = [0.0, 0.0, 0.0]
resolution = [64, 64]

[[object]]
shape = {{ type = "plane", size = {size}, divisions = 48 }}
material = {{ type = "translucent", preset = "{preset}", mm_per_unit = 1.0, model = "dipole" }}
casts_shadow = false

[[light]]
type = "directional"
direction = [0.0, 1.0, 0.0]
irradiance = [1.0, 1.0, 1.0]

[sampling]
method = "poisson"
count = {samples}
{extra}
"#,
        h = size,
        z = 0.5 * size
    )
}

/// The built-in scene, prepared with `overrides`, at the seed's 400 samples unless they name a
/// count: the tests' figures and their f64 twins' cost were set at 400, and the scene's own
/// default (an error target of 1%, about 30k samples) is what `tests/golden.rs` draws.
pub fn builtin(overrides: &Overrides) -> PreparedScene {
    let overrides = Overrides { samples: overrides.samples.or(Some(400)), ..overrides.clone() };
    PreparedScene::new(&Scene::builtin(), &overrides).unwrap()
}

/// A renderer for `prepared` that has drawn one full frame.
pub fn run_all(gpu: &Arc<Gpu>, prepared: PreparedScene) -> Renderer {
    let mut renderer = Renderer::new(gpu, prepared).expect("renderer");
    let plan = renderer.plan(Change::Everything);
    renderer.frame(&plan).expect("frame");
    renderer
}

/// The GPU gather alone, fed the given per-sample irradiance (from the f64 reference): the
/// exitance of object 0's vertices.
pub fn gather_from(gpu: &Arc<Gpu>, prepared: PreparedScene, irradiance: &[[f64; 3]]) -> Vec<[f32; 3]> {
    let mut renderer = Renderer::new(gpu, prepared).unwrap();
    let as_f32: Vec<[f32; 3]> = irradiance.iter().map(|e| e.map(|v| v as f32)).collect();
    set_splat_irradiance(&mut renderer, &as_f32);
    let mut plan = renderer.plan(Change::Everything);
    plan.passes.retain(|(p, _)| *p == Pass::Gather);
    // Every vertex, whatever level of detail the view would pick.
    plan.objects.iter_mut().for_each(|o| o.level = 0);
    renderer.frame(&plan).unwrap();
    renderer.exitance(0).unwrap()
}

/// Replace the splat output by `irradiance` (RGB per sample, scene order) with the near energies
/// computed on the CPU, so the gather gets the same input as the reference.
fn set_splat_irradiance(renderer: &mut Renderer, irradiance: &[[f32; 3]]) {
    let mut records = Vec::with_capacity(irradiance.len());
    for o in &renderer.scene().objects {
        for s in &o.samples {
            let near = match &o.material {
                ResolvedMaterial::Translucent { dipoles, .. } => {
                    let b = kernel::B_PER_SQRT_AREA * s.area.sqrt();
                    [0, 1, 2].map(|c| kernel::near_energy(&dipoles[c], b) as f32)
                }
                ResolvedMaterial::Opaque { .. } => [0.0; 3],
            };
            // Light along the inward normal: the dipole gathers these tests feed do not read it.
            let beam = (-s.normal).to_array();
            records.push(SplatRecord::new(irradiance[records.len()], s.area as f32, near, beam));
        }
    }
    renderer
        .scene_data_mut()
        .buffers_mut()
        .get_mut(translucent::render::graph::Resource::Splat)
        .unwrap()
        .write(0, &records)
        .unwrap();
}

//! The between-points single scattering in the renderer (`glsl/beam_gather.comp`) against its
//! f64 twin: the same table (`optics::beam_table`) read in f64 and summed over the same samples
//! with the density correction, per vertex; and the channels the material's `model` leaves to
//! the dipole untouched.

mod common;

use glam::DVec3;
use translucent::optics::beam_table::BeamTable;
use translucent::optics::directional_dipole::refract_in;
use translucent::render::beam_gather::{ObjectBeams, object_tables};
use translucent::render::plan::Change;
use translucent::render::renderer::Renderer;
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedObject, PreparedScene};

/// The light's direction towards it.
const LIGHT: [f64; 3] = [0.8, 0.5, 0.3];

/// A 2 cm sphere of ketchup (1 unit = 1 mm) with `model`, under one directional light.
fn ketchup(model: &str) -> PreparedScene {
    let text = format!(
        r#"
[camera]
eye = [0.0, 12.0, 45.0]
target = [0.0, 0.0, 0.0]
resolution = [32, 32]

[[object]]
shape = {{ type = "sphere", radius = 10.0, divisions = 12 }}
material = {{ type = "translucent", preset = "ketchup", mm_per_unit = 1.0, model = "{model}" }}
casts_shadow = false

[[light]]
type = "directional"
direction = {LIGHT:?}
irradiance = [1.0, 1.0, 1.0]

[sampling]
count = 3000
"#
    );
    PreparedScene::new(&Scene::parse(&text, "test.toml", None).unwrap(), &Overrides::default()).unwrap()
}

/// One full frame gathered at every vertex; the exitance of object 0, the splat's transmitted
/// irradiance per sample and the plan as `plan` prints it.
fn frame(prepared: PreparedScene) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, String) {
    common::with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, prepared).unwrap();
        let mut plan = renderer.plan(Change::Everything);
        plan.objects.iter_mut().for_each(|o| o.level = 0);
        renderer.frame(&plan).unwrap();
        let splat = renderer.splat_irradiance().unwrap().into_iter().map(|(e, _)| e).collect();
        (renderer.exitance(0).unwrap(), splat, plan.to_string())
    })
}

/// The f64 twin of glsl/beam_gather.comp at vertex `x`: the samples' `A E T` against their
/// `A T(rho, 1, 1)`, times `R1(1)`, in channel `c`.
fn twin(o: &PreparedObject, beams: &ObjectBeams, table: &BeamTable, c: usize, splat: &[[f32; 3]], x: DVec3) -> f64 {
    let light = DVec3::from(LIGHT).normalize();
    let eta = eta_of(o);
    let (mut sum, mut norm) = (0.0, 0.0);
    for (s, e) in o.samples.iter().zip(splat) {
        let (p, n) = (s.position.as_dvec3(), s.normal.as_dvec3());
        let d = x - p;
        let dist = d.length();
        if dist >= f64::from(beams.reach) {
            continue;
        }
        // The splat's beam: the light's refracted direction where it reaches the sample.
        let w = if e[c] > 0.0 { refract_in(light, n, eta).unwrap() } else { -n };
        let mu = (-w.dot(n)).clamp(0.0, 1.0);
        let (dt, wt) = (d - d.dot(n) * n, w + mu * n);
        let len = dt.length() * wt.length();
        let cos_phi = if len > 0.0 { dt.dot(wt) / len } else { 1.0 };
        let rho = dist * f64::from(beams.sigma_t[c]);
        sum += s.area * f64::from(e[c]) * table.lookup(rho, cos_phi, mu);
        norm += s.area * table.lookup(rho, 1.0, 1.0);
    }
    if norm > 0.0 { table.normal_total * sum / norm } else { 0.0 }
}

fn eta_of(o: &PreparedObject) -> f64 {
    match &o.material {
        translucent::scene::build::ResolvedMaterial::Translucent { dipoles, .. } => dipoles[0].eta,
        _ => unreachable!("the sphere is translucent"),
    }
}

#[test]
fn the_gpu_between_points_sum_matches_its_f64_twin_and_leaves_the_dipoles_channels_alone() {
    let auto = ketchup("auto");
    let object = auto.objects[0].clone();
    // Ketchup's red has alpha' 0.75, green and blue 0.067 and 0.020: `auto` gives them to
    // single scattering between points.
    assert_eq!(object.single_channels(), [false, true, true]);
    let (ours, splat, plan) = frame(auto);
    let (dipole, _, plain) = frame(ketchup("dipole"));
    // The plan says which channels take the model and why; the dipole's plan says nothing of it.
    assert!(plan.contains("G single scattering between points") && plan.contains("B single scattering"), "{plan}");
    assert!(!plan.contains("R single") && !plain.contains("single scattering"), "{plan}\n{plain}");
    let (beams, tables) = object_tables(&object, 1).unwrap();
    let positions = object.mesh.positions();
    let brightest = ours.iter().map(|m| m[1].max(m[2])).fold(0.0f32, f32::max);
    assert!(brightest > 0.0);
    let mut worst = 0.0f64;
    for (v, (m, d)) in ours.iter().zip(&dipole).enumerate() {
        assert!(m.iter().all(|x| x.is_finite() && *x >= 0.0), "vertex {v}: {m:?}");
        // The dipole's channel is what the dipole gather wrote, bit for bit.
        assert_eq!(m[0].to_bits(), d[0].to_bits(), "vertex {v}: red {} against the dipole's {}", m[0], d[0]);
        for c in [1, 2] {
            let expect = twin(&object, &beams, tables[c].as_ref().unwrap(), c, &splat, positions[v].as_dvec3());
            worst = worst.max((f64::from(m[c]) - expect).abs() / f64::from(brightest));
        }
    }
    eprintln!("worst difference from the f64 twin: {worst:.2e} of the brightest vertex");
    assert!(worst < 1e-3, "the GPU sum is {worst:.2e} of the brightest vertex from its f64 twin");
    // Green and blue are the model's, not the dipole's: they differ at some vertex.
    assert!(ours.iter().zip(&dipole).any(|(m, d)| (m[1] - d[1]).abs() > 0.05 * d[1].abs().max(1e-6)));
}

#[test]
fn a_between_points_model_with_the_pixel_gather_is_refused_with_the_key_to_change() {
    let mut prepared = ketchup("auto");
    prepared.scene.file.render.gather = translucent::scene::GatherMode::Pixel;
    let err = common::with_gpu(|gpu| Renderer::new(gpu, prepared).err().expect("refused").to_string());
    assert!(err.contains("material.model") && err.contains("render.gather"), "{err}");
}

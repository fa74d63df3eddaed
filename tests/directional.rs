//! The directional dipole's exitance at the vertices (`reference::directional`): its quadrature
//! checked against the truth with the standard dipole's kernel, and by its own convergence.

use glam::DVec3;
use translucent::optics::directional_dipole::{Diffusion, Strength};
use translucent::reference::{directional, truth};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene, ResolvedMaterial};
use translucent::study::vertex_error_f64;

/// A sphere of radius 10 (1 unit = 1 mm), `divisions`, of `preset`, under one directional light.
fn sphere(preset: &str, divisions: u32) -> PreparedScene {
    let text = format!(
        r#"
[camera]
eye = [0.0, 40.0, 80.0]
target = [0.0, 0.0, 0.0]
resolution = [32, 32]

[[object]]
shape = {{ type = "sphere", radius = 10.0, divisions = {divisions} }}
material = {{ type = "translucent", preset = "{preset}", mm_per_unit = 1.0 }}
casts_shadow = false

[[light]]
type = "directional"
direction = [0.8, 0.5, 0.3]
irradiance = [1.0, 1.0, 1.0]
"#
    );
    PreparedScene::new(&Scene::parse(&text, "test.toml", None).unwrap(), &Overrides::default()).unwrap()
}

#[test]
fn with_the_standard_dipoles_kernel_the_quadrature_matches_the_truth_within_a_tenth_of_a_percent() {
    for preset in ["marble", "ketchup"] {
        let scene = sphere(preset, 6);
        let ResolvedMaterial::Translucent { dipoles, .. } = &scene.objects[0].material else { panic!() };
        let dipoles = *dipoles;
        let r_d = move |c: usize, x_i: DVec3, _: DVec3, _: DVec3, x_o: DVec3, _: DVec3| {
            dipoles[c].r_d_sq(x_i.distance_squared(x_o))
        };
        let t = truth::compute(&scene, &truth::TruthOptions::default(), &|_, _, _| {}).unwrap();
        let ours =
            directional::exitance_with(&scene, Diffusion::Grosjean, Strength::Paper, directional::FINENESS, Some(&r_d));
        let e = vertex_error_f64(&t.exitance, &ours);
        eprintln!(
            "{preset}: R_d by the directional quadrature against the truth: RMS {:?}, bias {:?}",
            e.rel_rms, e.bias
        );
        assert!(e.rel_rms.iter().all(|v| *v < 0.001), "{preset}: {:?}", e.rel_rms);
    }
}

#[test]
fn the_directional_exitance_changes_under_a_tenth_of_a_percent_when_the_quadrature_is_twice_as_fine() {
    for preset in ["marble", "ketchup"] {
        let scene = sphere(preset, 6);
        let coarse =
            directional::exitance_with(&scene, Diffusion::Grosjean, Strength::Paper, directional::FINENESS, None);
        let fine =
            directional::exitance_with(&scene, Diffusion::Grosjean, Strength::Paper, 0.5 * directional::FINENESS, None);
        let e = vertex_error_f64(&fine, &coarse);
        eprintln!("{preset}: fineness {} against half of it: RMS {:?}", directional::FINENESS, e.rel_rms);
        assert!(e.rel_rms.iter().all(|v| *v < 0.001), "{preset}: {:?}", e.rel_rms);
    }
}

/// What the quadrature costs on the study's spheres, and how much it changes at half the
/// fineness there (run by hand).
#[test]
#[ignore = "a measurement; run by hand"]
fn cost_and_convergence_on_the_study_spheres() {
    for name in ["sphere-marble", "sphere-ketchup"] {
        let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("assets/scenes/{name}.toml"));
        let scene = PreparedScene::new(&Scene::load(&path).unwrap(), &Overrides::default()).unwrap();
        let mut previous: Option<Vec<Vec<[f64; 3]>>> = None;
        for fineness in [directional::FINENESS, 0.5 * directional::FINENESS] {
            let start = std::time::Instant::now();
            let m = directional::exitance_with(&scene, Diffusion::Grosjean, Strength::Paper, fineness, None);
            eprintln!("{name}: {} vertices, fineness {fineness}: {:.1} s", m[0].len(), start.elapsed().as_secs_f64());
            if let Some(p) = &previous {
                eprintln!("  change from the coarser: RMS {:?}", vertex_error_f64(&m, p).rel_rms);
            }
            previous = Some(m);
        }
    }
}

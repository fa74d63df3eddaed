//! Where on a sphere the dipole's model error is (issue 26): `rte_terminator SCENE SECONDS`
//! walks the radiative-transfer reference of the scene's first object for SECONDS (seed 1),
//! computes the dipole truth (its exact integral), and prints per channel the per-vertex
//! relative error of the truth against the reference over the vertices lit at least 1% of the
//! brightest (as the study's model error), split by the cosine between the vertex normal and
//! the direction to the scene's one directional light: RMS, mean, count, and each band's share
//! of the total squared error; with the reference's own relative noise in each band.
use translucent::reference::rte::{Budget, RteProgress};
use translucent::reference::rte_mesh::{self, MeshOptions, Walk};
use translucent::reference::truth::{self, LIT_FLOOR};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};
use translucent::scene::lights::LightKind;

/// The cosine bands, as [low, high).
const BANDS: [(f64, f64); 5] = [(0.5, 1.01), (0.2, 0.5), (0.0, 0.2), (-0.2, 0.0), (-1.01, -0.2)];

fn quiet(_: RteProgress) {}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene =
        PreparedScene::new(&Scene::load(std::path::Path::new(&args[1])).unwrap(), &Overrides::default()).unwrap();
    let seconds: f64 = args[2].parse().unwrap();
    let budget = Budget { max_photons: u64::MAX / 2, relative_stderr: None, max_seconds: Some(seconds) };
    let rte = rte_mesh::exitance(&scene, &MeshOptions { budget, seed: 1, walk: Walk::Photons }, &quiet).unwrap();
    let rte = rte[0].as_ref().unwrap();
    let t = truth::compute(&scene, &truth::TruthOptions::default(), &|_, _, _| {}).unwrap();
    let LightKind::Directional { direction, .. } = scene.lights[0].kind else { panic!("one directional light") };
    let l = direction.as_dvec3().normalize();
    let normals = scene.objects[0].mesh.vertex_normals();
    println!("{} photons in {:.0} s, relative standard error {:.4}", rte.photons, rte.seconds, rte.relative_stderr);
    for c in 0..3 {
        let floor = LIT_FLOOR * rte.exitance.iter().map(|m| m[c]).fold(0.0, f64::max);
        let lit: Vec<usize> =
            (0..rte.exitance.len()).filter(|&v| rte.exitance[v][c] > 0.0 && rte.exitance[v][c] >= floor).collect();
        let rel = |v: usize| t.exitance[0][v][c] / rte.exitance[v][c] - 1.0;
        let total: f64 = lit.iter().map(|&v| rel(v).powi(2)).sum();
        println!("channel {c}: {} lit, RMS {:.1}%", lit.len(), 100.0 * (total / lit.len() as f64).sqrt());
        for (lo, hi) in BANDS {
            let band: Vec<usize> = lit
                .iter()
                .copied()
                .filter(|&v| {
                    let cos = normals[v].as_dvec3().normalize().dot(l);
                    cos >= lo && cos < hi
                })
                .collect();
            if band.is_empty() {
                continue;
            }
            let n = band.len() as f64;
            let sq: f64 = band.iter().map(|&v| rel(v).powi(2)).sum();
            let mean = band.iter().map(|&v| rel(v)).sum::<f64>() / n;
            let noise = (band.iter().map(|&v| (rte.stderr[v][c] / rte.exitance[v][c]).powi(2)).sum::<f64>() / n).sqrt();
            println!(
                "  cos [{lo:+.1}, {hi:+.1}): {:4} vertices, RMS {:6.1}%, mean {:+6.1}%, share of the squared error {:5.1}%, reference noise {:.1}%",
                band.len(),
                100.0 * (sq / n).sqrt(),
                100.0 * mean,
                100.0 * sq / total,
                100.0 * noise
            );
        }
    }
}

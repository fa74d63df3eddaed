//! The adjoint reference against the photon walk: `adjoint_agreement SCENE SECONDS RECEIVERS`
//! walks the scene's first object both ways for SECONDS each (seed 1) and prints, per channel
//! and band of the cosine to the first light, the mean over the receivers lit in both of the
//! ratio adjoint / photons, with the standard error of that mean from both walks' errors.
use translucent::reference::rte::{Budget, RteProgress};
use translucent::reference::rte_mesh::{self, MeshOptions, Walk};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

fn quiet(_: RteProgress) {}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene =
        PreparedScene::new(&Scene::load(std::path::Path::new(&args[1])).unwrap(), &Overrides::default()).unwrap();
    let seconds: f64 = args[2].parse().unwrap();
    let receivers: usize = args[3].parse().unwrap();
    let budget = Budget { max_photons: u64::MAX / 4, relative_stderr: None, max_seconds: Some(seconds) };
    let run = |walk| rte_mesh::exitance(&scene, &MeshOptions { budget, seed: 1, walk }, &quiet).unwrap()[0].clone().unwrap();
    let adjoint = run(Walk::Adjoint { receivers: Some(receivers) });
    let photons = run(Walk::Photons);
    let count = scene.objects[0].mesh.positions().len();
    let (a, sa) = adjoint.per_vertex(count);
    let (p, sp) = (photons.exitance.clone(), photons.stderr.clone());
    println!("adjoint: {} walks per receiver; photons: {}", adjoint.photons, photons.photons);
    let cos = translucent::study::physics::light_cosines(&scene);
    for c in 0..3 {
        let max = p.iter().map(|m| m[c]).fold(0.0, f64::max);
        for (lo, hi) in [(0.5, 1.01), (0.0, 0.5), (-1.01, 0.0)] {
            let pairs: Vec<(f64, f64)> = (0..count)
                .filter(|&v| !a[v][c].is_nan() && p[v][c] >= 0.05 * max && cos[0][v] >= lo && cos[0][v] < hi)
                .map(|v| {
                    let r = a[v][c] / p[v][c];
                    let rel = ((sa[v][c] / a[v][c]).powi(2) + (sp[v][c] / p[v][c]).powi(2)).sqrt();
                    (r, r * rel)
                })
                .collect();
            if pairs.is_empty() {
                continue;
            }
            let n = pairs.len() as f64;
            let mean = pairs.iter().map(|x| x.0).sum::<f64>() / n;
            let se = pairs.iter().map(|x| x.1 * x.1).sum::<f64>().sqrt() / n;
            println!("channel {c}, cos [{lo:+.1}, {hi:+.1}): {} receivers, adjoint / photons {mean:.4} ± {se:.4}", pairs.len());
        }
    }
}

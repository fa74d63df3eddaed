//! Where the adjoint reference's noise is: `adjoint_noise SCENE WALKS [RECEIVERS]` walks the
//! scene's first object backwards from its receivers (seed 1) and prints, per band of the cosine
//! between the vertex normal and the first light, the lit receivers' median and RMS relative
//! standard error in the green channel, with the mean exitance.
use translucent::reference::rte::{Budget, RteProgress};
use translucent::reference::rte_mesh::{self, MeshOptions, Walk};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

fn quiet(_: RteProgress) {}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene =
        PreparedScene::new(&Scene::load(std::path::Path::new(&args[1])).unwrap(), &Overrides::default()).unwrap();
    let walks: u64 = args[2].parse().unwrap();
    let receivers = args.get(3).map(|r| r.parse().unwrap());
    let options = MeshOptions { budget: Budget::photons(walks), seed: 1, walk: Walk::Adjoint { receivers } };
    let rte = rte_mesh::exitance(&scene, &options, &quiet).unwrap();
    let o = rte[0].as_ref().unwrap();
    let cos = translucent::study::physics::light_cosines(&scene);
    let c = 1;
    let max = o.exitance.iter().map(|m| m[c]).fold(0.0, f64::max);
    println!("{} walks per receiver, {:.1} s, precision {:.4}", o.photons, o.seconds, o.relative_stderr);
    let mean = [0, 1, 2].map(|c| o.exitance.iter().map(|m| m[c]).sum::<f64>() / o.exitance.len() as f64);
    println!("mean exitance over the receivers (r, g, b): {:.5e} {:.5e} {:.5e}", mean[0], mean[1], mean[2]);
    for (lo, hi) in [(0.5, 1.01), (0.2, 0.5), (0.0, 0.2), (-0.2, 0.0), (-0.6, -0.2), (-1.01, -0.6)] {
        let mut rel: Vec<(f64, f64)> = o
            .receivers
            .as_ref()
            .unwrap()
            .iter()
            .enumerate()
            .filter(|(k, v)| cos[0][**v] >= lo && cos[0][**v] < hi && o.exitance[*k][c] >= 0.01 * max)
            .map(|(k, _)| (o.stderr[k][c] / o.exitance[k][c], o.exitance[k][c] / max))
            .collect();
        rel.sort_by(|a, b| a.0.total_cmp(&b.0));
        if rel.is_empty() {
            continue;
        }
        let rms = (rel.iter().map(|r| r.0 * r.0).sum::<f64>() / rel.len() as f64).sqrt();
        let mean = rel.iter().map(|r| r.1).sum::<f64>() / rel.len() as f64;
        println!(
            "cos [{lo:+.1}, {hi:+.1}): {:4} lit, relative stderr median {:.3} RMS {:.3} max {:.3}; exitance / max {:.3}",
            rel.len(),
            rel[rel.len() / 2].0,
            rms,
            rel[rel.len() - 1].0,
            mean
        );
    }
}

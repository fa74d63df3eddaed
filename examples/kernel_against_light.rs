//! The transport kernel against the light without the exact dipole integral, which on the
//! built-in bunny takes half an hour the first time: `kernel_against_light SCENE SECONDS
//! RECEIVERS` scales the f64 gather at the scene's own samples (the renderer's twin, within
//! about 1% of the exact integral at the defaults) by the first object's cached kernel
//! (`transport_cache::model_exitance`), walks the adjoint reference at RECEIVERS vertices for
//! SECONDS (seed 1), and prints per channel, over the receivers lit at least 1% of the
//! brightest: the relative RMS error of the kernel's model and of the gather alone (the dipole),
//! their mean bias, and the reference's own noise.
use translucent::reference::rte::{Budget, RteProgress};
use translucent::reference::rte_mesh::{self, MeshOptions, Walk};
use translucent::reference::{self, transport_cache, truth};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

fn quiet(_: RteProgress) {}

/// Over the receivers of `reference` lit at least 1% of its brightest in channel `c`: the
/// relative RMS error and mean bias of `model`, and the reference's noise.
fn against(model: &[[f64; 3]], (reference, se): &(Vec<[f64; 3]>, Vec<[f64; 3]>), c: usize) -> [f64; 3] {
    let max = reference.iter().map(|m| m[c]).filter(|m| m.is_finite()).fold(0.0, f64::max);
    let lit: Vec<usize> = (0..reference.len()).filter(|&v| reference[v][c] >= 0.01 * max).collect();
    let n = lit.len().max(1) as f64;
    let rel = |v: usize| model[v][c] / reference[v][c] - 1.0;
    let rms = (lit.iter().map(|&v| rel(v).powi(2)).sum::<f64>() / n).sqrt();
    let bias = lit.iter().map(|&v| rel(v)).sum::<f64>() / n;
    let noise = (lit.iter().map(|&v| (se[v][c] / reference[v][c]).powi(2)).sum::<f64>() / n).sqrt();
    [rms, bias, noise]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene =
        PreparedScene::new(&Scene::load(std::path::Path::new(&args[1])).unwrap(), &Overrides::default()).unwrap();
    let seconds: f64 = args[2].parse().unwrap();
    let receivers: usize = args[3].parse().unwrap();
    let gathered = reference::gather(&scene, &reference::splat(&scene, &reference::occluders(&scene)));
    let scaled =
        transport_cache::model_exitance(&scene, &gathered, &truth::default_cache_dir(), &|_, _, _| {}).unwrap();
    let budget = Budget { max_photons: u64::MAX, relative_stderr: None, max_seconds: Some(seconds) };
    let options = MeshOptions { budget, seed: 1, walk: Walk::Adjoint { receivers: Some(receivers) } };
    let walked = rte_mesh::exitance(&scene, &options, &quiet).unwrap().remove(0).unwrap();
    let reference = walked.per_vertex(gathered[0].len());
    println!("{} walks per receiver in {:.0} s", walked.photons, walked.seconds);
    for c in 0..3 {
        let [kernel, dipole] = [&scaled[0], &gathered[0]].map(|m| against(m, &reference, c));
        println!(
            "channel {c}: kernel {:.2}% (bias {:+.2}%), noise out {:.2}%; dipole {:.2}% (bias {:+.2}%); reference noise {:.2}%",
            100.0 * kernel[0],
            100.0 * kernel[1],
            100.0 * (kernel[0].powi(2) - kernel[2].powi(2)).max(0.0).sqrt(),
            100.0 * dipole[0],
            100.0 * dipole[1],
            100.0 * kernel[2]
        );
    }
}

//! Measurement of the closed-mesh radiative-transfer reference's efficiency (issue 26):
//! `rte_speed SECONDS SEED SCENE...` walks each scene's first object for SECONDS (or, with
//! `PHOTONS=N`, exactly N photons) and prints the photons per second and, per channel, the
//! relative standard error (RMS over the lit vertices over their mean, as
//! `rte_mesh::relative_stderr`) with that figure extrapolated to 600 s by `1 / sqrt(time)`.
use translucent::reference::rte::{Budget, RteProgress};
use translucent::reference::rte_mesh::{self, MeshOptions, Walk};
use translucent::reference::truth::LIT_FLOOR;
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

fn quiet(_: RteProgress) {}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seconds: f64 = args[1].parse().unwrap();
    let seed: u64 = args[2].parse().unwrap();
    let photons: Option<u64> = std::env::var("PHOTONS").ok().map(|s| s.parse().unwrap());
    for path in &args[3..] {
        let scene =
            PreparedScene::new(&Scene::load(std::path::Path::new(path)).unwrap(), &Overrides::default()).unwrap();
        let budget = match photons {
            Some(n) => Budget::photons(n),
            None => Budget { max_photons: u64::MAX / 2, relative_stderr: None, max_seconds: Some(seconds) },
        };
        let result = rte_mesh::exitance(&scene, &MeshOptions { budget, seed, walk: Walk::Photons }, &quiet).unwrap();
        let r = result[0].as_ref().unwrap();
        let per_channel: Vec<f64> = (0..3).map(|c| channel_rel(&r.exitance, &r.stderr, c)).collect();
        let scale = (r.seconds / 600.0).sqrt();
        println!(
            "{path}: {} photons in {:.1} s ({:.0}/s), lost {:?}; rel stderr per channel {:.4} {:.4} {:.4} (worst {:.4}); at 600 s {:.4} {:.4} {:.4}",
            r.photons,
            r.seconds,
            r.photons as f64 / r.seconds,
            r.lost,
            per_channel[0],
            per_channel[1],
            per_channel[2],
            r.relative_stderr,
            per_channel[0] * scale,
            per_channel[1] * scale,
            per_channel[2] * scale,
        );
        let sums: Vec<f64> = (0..3).map(|c| r.exitance.iter().map(|m| m[c]).sum()).collect();
        let ses: Vec<f64> = (0..3).map(|c| r.stderr.iter().map(|s| s[c] * s[c]).sum::<f64>().sqrt()).collect();
        println!(
            "  summed exitance per channel {:.6e} ± {:.2e}, {:.6e} ± {:.2e}, {:.6e} ± {:.2e}",
            sums[0], ses[0], sums[1], ses[1], sums[2], ses[2]
        );
    }
}

/// One channel's relative standard error, as `rte_mesh::relative_stderr` measures it.
fn channel_rel(exitance: &[[f64; 3]], stderr: &[[f64; 3]], c: usize) -> f64 {
    let floor = LIT_FLOOR * exitance.iter().map(|m| m[c]).fold(0.0, f64::max);
    let lit: Vec<usize> = (0..exitance.len()).filter(|&v| exitance[v][c] > 0.0 && exitance[v][c] >= floor).collect();
    let n = lit.len() as f64;
    let mean = lit.iter().map(|&v| exitance[v][c]).sum::<f64>() / n;
    let se2 = lit.iter().map(|&v| stderr[v][c].powi(2)).sum::<f64>() / n;
    se2.sqrt() / mean
}

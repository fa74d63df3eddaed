//! The transport kernel against the light without the exact dipole integral, which on the
//! built-in bunny takes half an hour the first time: `kernel_against_light SCENE SECONDS
//! RECEIVERS [WALKS [PATCHES [SEED]]]` scales the f64 gather at the scene's own samples (the
//! renderer's twin, within about 1% of the exact integral at the defaults) by the first
//! object's kernel of WALKS walks per channel, at most PATCHES patches and kernel seed SEED
//! (the defaults, `KernelSettings::default()`, where left out; cached by content), walks the
//! adjoint reference at RECEIVERS vertices for SECONDS (seed 1; cached by content, so a second
//! run takes seconds), and prints per channel, over the receivers lit at least 1% of the
//! brightest: the relative RMS error of the kernel's model and of the gather alone (the dipole),
//! their mean bias, the reference's own noise, and the kernel's error split into the patches'
//! levels (each patch's mean error over its receivers) and the spread within a patch.
use translucent::reference::rte::{Budget, RteProgress};
use translucent::reference::rte_mesh::{KernelSettings, MeshOptions, Walk};
use translucent::reference::{self, rte_cache, transport_cache, truth};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

fn quiet(_: RteProgress) {}

/// Over the receivers of `reference` lit at least 1% of its brightest in channel `c`: the
/// relative RMS error and mean bias of `model`, and the reference's noise.
fn against(model: &[[f64; 3]], (reference, se): &(Vec<[f64; 3]>, Vec<[f64; 3]>), c: usize) -> [f64; 3] {
    let lit = lit(reference, c);
    let n = lit.len().max(1) as f64;
    let rel = |v: usize| model[v][c] / reference[v][c] - 1.0;
    let rms = (lit.iter().map(|&v| rel(v).powi(2)).sum::<f64>() / n).sqrt();
    let bias = lit.iter().map(|&v| rel(v)).sum::<f64>() / n;
    let noise = (lit.iter().map(|&v| (se[v][c] / reference[v][c]).powi(2)).sum::<f64>() / n).sqrt();
    [rms, bias, noise]
}

/// The receivers lit at least 1% of the brightest in channel `c`.
fn lit(reference: &[[f64; 3]], c: usize) -> Vec<usize> {
    let max = reference.iter().map(|m| m[c]).filter(|m| m.is_finite()).fold(0.0, f64::max);
    (0..reference.len()).filter(|&v| reference[v][c] >= 0.01 * max).collect()
}

/// `model`'s relative RMS error in channel `c` split in two: the RMS over the lit receivers of
/// their patch's mean error (the patches' levels), and of each one's error less that mean (the
/// spread within a patch).
fn by_patch(model: &[[f64; 3]], reference: &[[f64; 3]], of_vertex: &[u32], c: usize) -> [f64; 2] {
    let lit = lit(reference, c);
    let rel = |v: usize| model[v][c] / reference[v][c] - 1.0;
    let mut sums = std::collections::HashMap::<u32, (f64, f64)>::new();
    lit.iter().for_each(|&v| {
        let s = sums.entry(of_vertex[v]).or_default();
        *s = (s.0 + rel(v), s.1 + 1.0);
    });
    let mean = |v: usize| sums[&of_vertex[v]].0 / sums[&of_vertex[v]].1;
    let n = lit.len().max(1) as f64;
    let level = (lit.iter().map(|&v| mean(v).powi(2)).sum::<f64>() / n).sqrt();
    let within = (lit.iter().map(|&v| (rel(v) - mean(v)).powi(2)).sum::<f64>() / n).sqrt();
    [level, within]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, default: u64| args.get(i).map_or(default, |a| a.parse().expect("a whole number"));
    let scene =
        PreparedScene::new(&Scene::load(std::path::Path::new(&args[1])).unwrap(), &Overrides::default()).unwrap();
    let seconds: f64 = args[2].parse().unwrap();
    let receivers: usize = args[3].parse().unwrap();
    let d = KernelSettings::default();
    let settings = KernelSettings {
        walks: arg(4, d.walks),
        patches: arg(5, d.patches as u64) as usize,
        seed: arg(6, d.seed),
        ..d
    };
    let dir = truth::default_cache_dir();
    let gathered = reference::gather(&scene, &reference::splat(&scene, &reference::occluders(&scene)));
    let scaled = transport_cache::model_exitance_with(&scene, &gathered, &settings, &dir, &|_, _, _| {}).unwrap();
    let (kernel, _) = transport_cache::cached(&scene.objects[0], &settings, &dir, &|_, _| {}).unwrap();
    let budget = Budget { max_photons: u64::MAX, relative_stderr: None, max_seconds: Some(seconds) };
    let options = MeshOptions { budget, seed: 1, walk: Walk::Adjoint { receivers: Some(receivers) } };
    let (walked, cached) = rte_cache::cached(&scene, &options, &dir, &quiet).unwrap();
    let walked = walked.objects[0].as_ref().expect("the first object is translucent");
    let reference = walked.per_vertex(gathered[0].len());
    let how = if cached { "cached" } else { "walked" };
    println!("reference {how}: {} walks per receiver in {:.0} s", walked.photons, walked.seconds);
    println!("kernel: {} walks per channel, {} patches, seed {}", settings.walks, kernel.patches.len(), settings.seed);
    for c in 0..3 {
        let [kernel_error, dipole] = [&scaled[0], &gathered[0]].map(|m| against(m, &reference, c));
        let [level, within] = by_patch(&scaled[0], &reference.0, &kernel.patches.of_vertex, c);
        println!(
            "channel {c}: kernel {:.2}% (bias {:+.2}%), noise out {:.2}%, patch levels {:.2}%, within patches {:.2}%; \
             dipole {:.2}% (bias {:+.2}%); reference noise {:.2}%",
            100.0 * kernel_error[0],
            100.0 * kernel_error[1],
            100.0 * (kernel_error[0].powi(2) - kernel_error[2].powi(2)).max(0.0).sqrt(),
            100.0 * level,
            100.0 * within,
            100.0 * dipole[0],
            100.0 * dipole[1],
            100.0 * kernel_error[2]
        );
    }
}

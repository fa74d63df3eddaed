//! Walk the transport kernel of every translucent object of a scene (not cached) and print its
//! patches, walks, wall time, the flux it sends out per unit flux in against the dipole's
//! `R_d,total`, and its device memory: `cargo run --release --example transport_kernel --
//! SCENE|default [PATCHES] [WALKS]` (defaults: `KernelSettings::default()`). The figures of
//! docs/PHYSICS.md's precompute table.
use translucent::reference::rte_mesh::{KernelSettings, object_kernel};
use translucent::scene::build::{PreparedScene, ResolvedMaterial};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = match args.get(1).map(String::as_str) {
        None | Some("default") => translucent::scene::Scene::builtin(),
        Some(path) => translucent::scene::Scene::load(std::path::Path::new(path)).unwrap(),
    };
    let prepared = PreparedScene::new(&scene, &Default::default()).unwrap();
    let d = KernelSettings::default();
    let settings = KernelSettings {
        patches: args.get(2).map_or(d.patches, |a| a.parse().unwrap()),
        walks: args.get(3).map_or(d.walks, |a| a.parse().unwrap()),
        ..d
    };
    for o in &prepared.objects {
        let ResolvedMaterial::Translucent { dipoles, .. } = &o.material else { continue };
        let start = std::time::Instant::now();
        let k = object_kernel(o, &settings, &|_, _| {}).unwrap();
        let seconds = start.elapsed().as_secs_f64();
        let n = k.patches.len();
        let out = [0, 1, 2].map(|c| k.flux[c].iter().sum::<f64>() / n as f64);
        let ld = dipoles.map(|d| d.diffusion_length());
        let radius = o.mesh.positions().iter().map(|p| p.length()).fold(0.0f32, f32::max);
        println!(
            "{}: {} vertices, {n} patches x {} walks, {seconds:.1} s; out per unit in {:.3} {:.3} {:.3} \
             (dipole R_d,total {:.3} {:.3} {:.3}); diffusion length {:.2e} {:.2e} {:.2e}, extent {radius:.2e}; {:.2} MiB",
            o.name,
            o.mesh.positions().len(),
            k.walks,
            out[0],
            out[1],
            out[2],
            dipoles[0].r_d_total(),
            dipoles[1].r_d_total(),
            dipoles[2].r_d_total(),
            ld[0],
            ld[1],
            ld[2],
            k.device_bytes() as f64 / (1u64 << 20) as f64,
        );
    }
}

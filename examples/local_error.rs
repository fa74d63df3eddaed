//! Per-vertex error of the local model `M = R_d,total E_t` (what `render.transport = "local"`
//! and the planner's local channels shade) against the exact dipole integral, per channel:
//! `cargo run --release --example local_error -- SCENE [CACHE_DIR]`. The truth is read from
//! (or written to) the cache folder, as `translucent study` keeps it; `E_t` at each vertex is
//! the truth's own (`reference::transmitted_irradiance`, ray-cast shadows).
use translucent::reference::{self, truth};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene, ResolvedMaterial};
use translucent::scene::{GatherMode, TransportMode};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = Scene::load(std::path::Path::new(&args[1])).unwrap();
    // Prepared as the study prepares it, so the truth's content key matches its cache.
    let overrides =
        Overrides { transport: Some(TransportMode::Gather), gather: Some(GatherMode::Vertex), ..Overrides::default() };
    let scene = PreparedScene::new(&scene, &overrides).unwrap();
    let dir = args.get(2).map_or_else(truth::default_cache_dir, std::path::PathBuf::from);
    let (t, cached) = truth::cached(&scene, &truth::TruthOptions::default(), &dir, &|_, _, _| {}).unwrap();
    println!("truth: converged {}, change {:.2e}, cached {cached}", t.converged, t.change());
    let occluders = reference::occluders(&scene);
    let eps = reference::ray_offset(&scene);
    for (i, o) in scene.objects.iter().enumerate() {
        let ResolvedMaterial::Translucent { material, dipoles, .. } = &o.material else { continue };
        let normals = o.mesh.vertex_normals();
        let local: Vec<[f64; 3]> = o
            .mesh
            .positions()
            .iter()
            .zip(normals)
            .map(|(p, n)| {
                let (e, _, _) = reference::transmitted_irradiance(
                    &scene,
                    &occluders,
                    p.as_dvec3(),
                    n.as_dvec3(),
                    material.eta,
                    eps,
                );
                [0, 1, 2].map(|c| dipoles[c].r_d_total() * e[c])
            })
            .collect();
        let estimate: Vec<Vec<[f32; 3]>> = scene
            .objects
            .iter()
            .enumerate()
            .map(|(j, oj)| {
                if j == i {
                    local.iter().map(|m| m.map(|x| x as f32)).collect()
                } else {
                    vec![[0.0; 3]; oj.mesh.positions().len()]
                }
            })
            .collect();
        let only: Vec<Vec<[f64; 3]>> = t
            .exitance
            .iter()
            .enumerate()
            .map(|(j, m)| if j == i { m.clone() } else { vec![[0.0; 3]; m.len()] })
            .collect();
        let e = translucent::study::vertex_error(&only, &estimate);
        let pct = |v: [f64; 3]| format!("{:.3}% {:.3}% {:.3}%", 100.0 * v[0], 100.0 * v[1], 100.0 * v[2]);
        println!("{}: local model, per channel r g b", o.name);
        println!("  relative RMS {}\n  p99 {}\n  bias {}", pct(e.rel_rms), pct(e.p99), pct(e.bias));
    }
}

//! Experiment: bias of the vertex gather's near field on a uniformly lit square, against the
//! exact integral. `near_bias METHOD COUNT [SEEDS]`.
use glam::DVec3;
use translucent::optics::kernel;
use translucent::reference::{self, truth};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene, ResolvedMaterial};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (method, count) = (&args[1], &args[2]);
    let seeds: u64 = args.get(3).map_or(3, |s| s.parse().unwrap());
    let text = |seed: u64| {
        format!(
            "[camera]\neye = [0.0, 40.0, 80.0]\ntarget = [0.0, 0.0, 0.0]\nresolution = [32, 32]\n\
[[object]]\nshape = {{ type = \"plane\", size = 60.0, divisions = 60 }}\n\
material = {{ type = \"translucent\", preset = \"marble\", mm_per_unit = 10.0 }}\ncasts_shadow = false\n\
[[light]]\ntype = \"directional\"\ndirection = [0.0, 1.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]\n\
[sampling]\nmethod = \"{method}\"\ncount = {count}\nseed = {seed}\n"
        )
    };
    let base = PreparedScene::new(&Scene::parse(&text(1), "p", None).unwrap(), &Overrides::default()).unwrap();
    let t = truth::compute(&base, &truth::TruthOptions { max_level: 2, ..Default::default() }, &|_, _, _| {});
    let exact = &t.exitance[0];
    for seed in 1..=seeds {
        let scene = PreparedScene::new(&Scene::parse(&text(seed), "p", None).unwrap(), &Overrides::default()).unwrap();
        let o = &scene.objects[0];
        let ResolvedMaterial::Translucent { dipoles, .. } = &o.material else { panic!() };
        let irr = reference::splat(&scene, &reference::occluders(&scene));
        let m = &reference::gather(&scene, &irr)[0];
        // Shepard share of each sample by a fine grid over the square.
        let pts: Vec<(DVec3, f64)> = o.samples.iter().map(|s| (s.position.as_dvec3(), s.area)).collect();
        let h = (3600.0 / pts.len() as f64).sqrt() / 6.0;
        let n = (60.0 / h).ceil() as usize;
        let g = 60.0 / n as f64;
        let mut share = vec![0.0; pts.len()];
        for i in 0..n {
            for j in 0..n {
                let y = DVec3::new(-30.0 + (i as f64 + 0.5) * g, 0.0, -30.0 + (j as f64 + 0.5) * g);
                let w: Vec<f64> = pts.iter().map(|(p, a)| kernel::near_blend_weight(y.distance(*p), *a)).collect();
                let sum: f64 = w.iter().sum();
                if sum > 0.0 {
                    w.iter().zip(&mut share).for_each(|(w, s)| *s += g * g * w / sum);
                } else {
                    let k =
                        (0..pts.len()).min_by(|&a, &b| y.distance(pts[a].0).total_cmp(&y.distance(pts[b].0))).unwrap();
                    share[k] += g * g;
                }
            }
        }
        let scale: Vec<f64> = pts.iter().zip(&share).map(|((_, a), s)| a / s).collect();
        let (smin, smax) = scale.iter().fold((f64::MAX, 0.0f64), |(a, b), &s| (a.min(s), b.max(s)));
        // Corrected near field.
        let corrected: Vec<[f64; 3]> = o
            .mesh
            .positions()
            .iter()
            .enumerate()
            .map(|(v, x)| {
                let x = x.as_dvec3();
                let (mut near, mut plain, mut wsum) = ([0.0; 3], [0.0; 3], 0.0);
                for (k, (p, a)) in pts.iter().enumerate() {
                    let w = kernel::near_blend_weight(x.distance(*p), *a);
                    wsum += w;
                    let b = kernel::B_PER_SQRT_AREA * a.sqrt();
                    for c in 0..3 {
                        let e = irr[k][c] * kernel::near_energy(&dipoles[c], b);
                        near[c] += w * e * scale[k];
                        plain[c] += w * e;
                    }
                }
                [0, 1, 2].map(|c| if wsum > 0.0 { m[v][c] + (near[c] - plain[c]) / wsum } else { m[v][c] })
            })
            .collect();
        let report = |name: &str, est: &[[f64; 3]]| {
            let (mut inner, mut ni, mut edge, mut ne, mut corner, mut nc) = ([0.0; 3], 0, [0.0; 3], 0, [0.0; 3], 0);
            for (v, x) in o.mesh.positions().iter().enumerate() {
                let (ax, az) = (x.x.abs(), x.z.abs());
                for c in 0..3 {
                    let r = est[v][c] / exact[v][c];
                    if ax < 25.0 && az < 25.0 {
                        inner[c] += r - 1.0;
                    } else if (ax > 29.99) ^ (az > 29.99) && ax.min(az) < 20.0 {
                        edge[c] += r;
                    } else if ax > 29.99 && az > 29.99 {
                        corner[c] += r;
                    }
                }
                if ax < 25.0 && az < 25.0 {
                    ni += 1;
                } else if (ax > 29.99) ^ (az > 29.99) && ax.min(az) < 20.0 {
                    ne += 1;
                } else if ax > 29.99 && az > 29.99 {
                    nc += 1;
                }
            }
            println!(
                "seed {seed} {name:9}: interior bias {:+.3}% {:+.3}% {:+.3}%  edge ratio {:.3} {:.3} {:.3}  corner ratio {:.3} {:.3} {:.3}",
                100.0 * inner[0] / ni as f64,
                100.0 * inner[1] / ni as f64,
                100.0 * inner[2] / ni as f64,
                edge[0] / ne as f64,
                edge[1] / ne as f64,
                edge[2] / ne as f64,
                corner[0] / nc as f64,
                corner[1] / nc as f64,
                corner[2] / nc as f64
            );
        };
        report("gather", m);
        report("corrected", &corrected);
        println!("   near scale range {smin:.3} .. {smax:.3}");
    }
}

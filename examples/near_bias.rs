//! Experiment: bias of the vertex gather (f64 twin) on a uniformly lit square, against the exact
//! integral: the interior (defect 1), the edges and the corners (defect 3). `near_bias METHOD
//! COUNT [SEEDS]`.
use translucent::reference::{self, truth};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

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
    let t = truth::compute(&base, &truth::TruthOptions { max_level: 2, ..Default::default() }, &|_, _, _| {}).unwrap();
    let exact = &t.exitance[0];
    for seed in 1..=seeds {
        let scene = PreparedScene::new(&Scene::parse(&text(seed), "p", None).unwrap(), &Overrides::default()).unwrap();
        let o = &scene.objects[0];
        let irr = reference::splat(&scene, &reference::occluders(&scene));
        let m = &reference::gather(&scene, &irr)[0];
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
    }
}

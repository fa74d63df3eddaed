//! Experiment for the study's defect 2 (the vertex gather reads low beside the terminator): the
//! f64 twin's error against the exact integral, binned by `n.l` at the vertex, split into what the
//! far sum and the near-field blend contribute, and the error over every lit vertex.
//! `terminator SCENE COUNT [CACHE_DIR]` (one directional light; the scene's sampler);
//! `BLEND_K=kr,kg,kb` replaces the blend's radii, `SKIP_SPLIT=1` skips the slow split,
//! `SAMPLER=random` replaces the scene's sampler. Defect 1's cures tried (docs/STUDY.md):
//! `UNIFORM_B=1` takes every sample's `b` from the object's mean area; `COMMON_R=1` blends with
//! weights `A_i phi(r / R(x))`, one radius per receiver from its local mean area.
use translucent::optics::kernel;
use translucent::reference::{self, truth};
use translucent::scene::build::{Overrides, PreparedScene, ResolvedMaterial};
use translucent::scene::lights::LightKind;
use translucent::scene::{GatherMode, Scene, TransportMode};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = Scene::load(std::path::Path::new(&args[1])).unwrap();
    let count: usize = args[2].parse().unwrap();
    let overrides = Overrides {
        transport: Some(TransportMode::Gather),
        gather: Some(GatherMode::Vertex),
        samples: Some(count),
        sampler: std::env::var("SAMPLER").ok().map(|m| m.parse().unwrap()),
        ..Overrides::default()
    };
    let scene = PreparedScene::new(&scene, &overrides).unwrap();
    let dir = args.get(3).map_or_else(truth::default_cache_dir, std::path::PathBuf::from);
    let (t, _) = truth::cached(&scene, &truth::TruthOptions::default(), &dir, &|_, _, _| {}).unwrap();
    let LightKind::Directional { direction, .. } = scene.lights[0].kind else { panic!("one directional light") };
    let l = direction.as_dvec3().normalize();
    let occluders = reference::occluders(&scene);
    let eps = reference::ray_offset(&scene);
    let irradiance = reference::splat(&scene, &occluders);
    let o = &scene.objects[0];
    let ResolvedMaterial::Translucent { dipoles, material, .. } = &o.material else { panic!() };
    let samples: Vec<_> = o.samples.iter().zip(&irradiance).collect();
    // The blend's radius factor per channel: the renderer's (kernel::near_blend_radii), or
    // BLEND_K=kr,kg,kb to try others (1.5,1.5,1.5 is the single radius used before).
    let k: [f64; 3] = match std::env::var("BLEND_K") {
        Ok(v) => {
            let k: Vec<f64> = v.split(',').map(|x| x.parse().unwrap()).collect();
            [k[0], k[1], k[2]]
        }
        Err(_) => o.near_blend_radii(),
    };
    println!("blend radius r/g/b: {:.3}/{:.3}/{:.3} sqrt(dA)", k[0], k[1], k[2]);
    let uniform_b = std::env::var("UNIFORM_B").is_ok();
    let mean_area_all = o.samples.iter().map(|s| s.area).sum::<f64>() / o.samples.len() as f64;
    let radius_sq: Vec<[f64; 3]> = o.samples.iter().map(|s| k.map(|k| k * k * s.area)).collect();
    let bins = [(-0.3, -0.1), (-0.1, 0.0), (0.0, 0.1), (0.1, 0.2), (0.2, 0.4), (0.4, 0.7)];
    // Per bin: sum of relative errors of (gather, far + exact near), near share, count.
    let mut acc = vec![([0.0f64; 3], [0.0f64; 3], [0.0f64; 3], [0.0f64; 3], 0usize); bins.len()];
    // The exact near part, integral R_near(|x - y|; b) E_t(y) dA(y), by brute force over the
    // triangles within reach (pieces of a twentieth of R_near's width), for the band's vertices.
    let mut split = vec![([0.0f64; 3], [0.0f64; 3], 0usize); bins.len()];
    let normals = o.mesh.vertex_normals();
    let mut estimate = vec![[0.0f32; 3]; o.mesh.positions().len()];
    for (v, (x, n)) in o.mesh.positions().iter().zip(normals).enumerate() {
        let (x, n) = (x.as_dvec3(), n.as_dvec3());
        let nl = n.dot(l);
        let (mut far, mut near, mut wsum, mut asum) = ([0.0; 3], [0.0; 3], [0.0; 3], 0.0);
        for ((s, e), rsq) in samples.iter().zip(&radius_sq) {
            let r = x.distance(s.position.as_dvec3());
            let b = kernel::B_PER_SQRT_AREA * if uniform_b { mean_area_all } else { s.area }.sqrt();
            asum += kernel::near_blend_weight(r, s.area, kernel::NEAR_BLEND_RADIUS) * s.area;
            for c in 0..3 {
                let t = if r * r < rsq[c] { 1.0 - r * r / rsq[c] } else { 0.0 };
                let w = t * t * t;
                wsum[c] += w;
                far[c] += e[c] * s.area * kernel::r_d_far(&dipoles[c], r, b);
                near[c] += w * e[c] * kernel::near_energy(&dipoles[c], b);
            }
        }
        let wsum1: f64 = samples
            .iter()
            .map(|(s, _)| {
                kernel::near_blend_weight(x.distance(s.position.as_dvec3()), s.area, kernel::NEAR_BLEND_RADIUS)
            })
            .sum();
        if std::env::var("COMMON_R").is_ok() && wsum1 > 0.0 {
            // One radius per receiver and channel, from the local mean area; weights A_i phi.
            let a_local = asum / wsum1;
            near = [0.0; 3];
            wsum = [0.0; 3];
            for (s, e) in samples.iter() {
                let r = x.distance(s.position.as_dvec3());
                let b = kernel::B_PER_SQRT_AREA * s.area.sqrt();
                for c in 0..3 {
                    let rsq = k[c] * k[c] * a_local;
                    let t = if r * r < rsq { 1.0 - r * r / rsq } else { 0.0 };
                    let w = s.area * t * t * t;
                    wsum[c] += w;
                    near[c] += w * e[c] * kernel::near_energy(&dipoles[c], b);
                }
            }
        }
        estimate[v] = std::array::from_fn(|c| (far[c] + if wsum[c] > 0.0 { near[c] / wsum[c] } else { 0.0 }) as f32);
        let Some(bin) = bins.iter().position(|&(a, b)| nl >= a && nl < b) else { continue };
        let (e_x, ..) = reference::transmitted_irradiance(&scene, &occluders, x, n, material.eta, eps);
        let b_mean = kernel::B_PER_SQRT_AREA * (asum / wsum1.max(1e-300)).sqrt();
        let exact = t.exitance[0][v];
        let a = &mut acc[bin];
        for c in 0..3 {
            if exact[c] <= 0.0 {
                continue;
            }
            let blend = if wsum[c] > 0.0 { near[c] / wsum[c] } else { 0.0 };
            let exact_near = e_x[c] * kernel::near_energy(&dipoles[c], b_mean);
            a.0[c] += (far[c] + blend - exact[c]) / exact[c];
            a.1[c] += (far[c] + exact_near - exact[c]) / exact[c];
            a.2[c] += blend / exact[c];
            a.3[c] += (blend - exact_near) / exact[c];
        }
        a.4 += 1;
        if nl.abs() < 0.2 || (0.4..0.7).contains(&nl) {
            let ell = (dipoles.iter().map(|d| d.z_v * d.z_v).fold(0.0, f64::max) + b_mean * b_mean).sqrt();
            let reach = 8.0 * ell;
            let mut exact_near = [0.0; 3];
            for tri in 0..o.mesh.triangles().len() {
                let [p0, p1, p2] = o.mesh.corners(tri);
                if x.distance(p0).min(x.distance(p1)).min(x.distance(p2)) > reach + p0.distance(p1).max(p1.distance(p2))
                {
                    continue;
                }
                let area = 0.5 * (p1 - p0).cross(p2 - p0).length();
                let m = ((p0.distance(p1).max(p1.distance(p2)).max(p2.distance(p0))) / (ell / 20.0)).ceil().max(1.0)
                    as usize;
                let each = area / (m * m) as f64;
                let inv = 1.0 / m as f64;
                let mut piece = |u: f64, w: f64| {
                    let bary = [1.0 - u - w, u, w];
                    let y = p0 * bary[0] + p1 * bary[1] + p2 * bary[2];
                    let r = x.distance(y);
                    if r > reach {
                        return;
                    }
                    let ny = o.mesh.normal_at(tri, bary).as_dvec3();
                    let (e, ..) = reference::transmitted_irradiance(&scene, &occluders, y, ny, material.eta, eps);
                    for c in 0..3 {
                        let near_k = (dipoles[c].r_d(r) - kernel::r_d_far(&dipoles[c], r, b_mean)).max(0.0);
                        exact_near[c] += near_k * e[c] * each;
                    }
                };
                for i in 0..m {
                    for j in 0..m - i {
                        piece((i as f64 + 1.0 / 3.0) * inv, (j as f64 + 1.0 / 3.0) * inv);
                        if i + j + 1 < m {
                            piece((i as f64 + 2.0 / 3.0) * inv, (j as f64 + 2.0 / 3.0) * inv);
                        }
                    }
                }
            }
            let sp = &mut split[bin];
            for c in 0..3 {
                if exact[c] <= 0.0 {
                    continue;
                }
                let blend = if wsum[c] > 0.0 { near[c] / wsum[c] } else { 0.0 };
                // far sum against exact far (truth - exact near), blend against exact near
                sp.0[c] += (far[c] - (exact[c] - exact_near[c])) / exact[c];
                sp.1[c] += (blend - exact_near[c]) / exact[c];
            }
            sp.2 += 1;
        }
    }
    let err = translucent::study::vertex_error(&t.exitance, &[estimate]);
    let pc = |v: [f64; 3]| format!("{:.3}/{:.3}/{:.3}%", 100.0 * v[0], 100.0 * v[1], 100.0 * v[2]);
    println!(
        "all lit vertices: rms {}  bias {}  p99 {}  max {}",
        pc(err.rel_rms),
        pc(err.bias),
        pc(err.p99),
        pc(err.max)
    );
    if std::env::var("SKIP_SPLIT").is_ok() {
        return;
    }
    println!("{} {count}: mean relative error per n.l bin, r/g/b", args[1]);
    for (bin, a) in bins.iter().zip(&acc) {
        let f = |v: [f64; 3]| mean_percent(v, a.4);
        println!(
            "[{:+.1},{:+.1}) n={:4}  gather {}  far+E_t(x)E_near {}  near share {}  blend-minus-local {}",
            bin.0,
            bin.1,
            a.4,
            f(a.0),
            f(a.1),
            f(a.2),
            f(a.3)
        );
    }
    println!("split against the exact near part (brute force):");
    for (bin, sp) in bins.iter().zip(&split) {
        if sp.2 == 0 {
            continue;
        }
        let f = |v: [f64; 3]| mean_percent(v, sp.2);
        println!(
            "[{:+.1},{:+.1}) n={:4}  far sum - exact far {}  blend - exact near {}",
            bin.0,
            bin.1,
            sp.2,
            f(sp.0),
            f(sp.1)
        );
    }
}

/// The mean of `n` summed relative errors per channel, as "r/g/b%".
fn mean_percent(sum: [f64; 3], n: usize) -> String {
    let m = sum.map(|v| 100.0 * v / n as f64);
    format!("{:+.2}/{:+.2}/{:+.2}%", m[0], m[1], m[2])
}

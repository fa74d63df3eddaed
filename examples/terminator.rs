//! Experiment for the study's defect 2 (the vertex gather reads low beside the terminator): the
//! f64 twin's error against the exact integral, binned by `n.l` at the vertex, split into what the
//! far sum and the near-field blend contribute, and the error over every lit vertex.
//! `terminator SCENE COUNT [CACHE_DIR]` (one directional light; the scene's sampler);
//! `BLEND_K=kr,kg,kb` replaces the blend's radii, `SKIP_SPLIT=1` skips the slow split,
//! `SAMPLER=random` replaces the scene's sampler. Defect 1's cures tried (docs/STUDY.md):
//! `UNIFORM_B=1` takes every sample's `b` from the object's mean area; `COMMON_R=1` blends with
//! weights `A_i phi(r / R(x))`, one radius per receiver from its local mean area.
use glam::DVec3;
use translucent::mesh::Mesh;
use translucent::optics::{Dipole, kernel};
use translucent::reference::bvh::Bvh;
use translucent::reference::{self, truth};
use translucent::sampling::SamplePoint;
use translucent::scene::build::{Overrides, PreparedObject, PreparedScene, ResolvedMaterial};
use translucent::scene::lights::LightKind;
use translucent::scene::{GatherMode, Scene, TransportMode};

/// The `n.l` bins the errors are reported in, narrow about the terminator (`n.l = 0`).
const BINS: [(f64, f64); 6] = [(-0.3, -0.1), (-0.1, 0.0), (0.0, 0.1), (0.1, 0.2), (0.2, 0.4), (0.4, 0.7)];

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
    let lighting = Lighting { scene: &scene, occluders: &occluders, eta: material.eta, eps };
    let gather = Gather::new(o, &irradiance, dipoles);
    println!("blend radius r/g/b: {:.3}/{:.3}/{:.3} sqrt(dA)", gather.k[0], gather.k[1], gather.k[2]);
    let mut acc = vec![BinErrors::default(); BINS.len()];
    // The exact near part, integral R_near(|x - y|; b) E_t(y) dA(y), by brute force over the
    // triangles within reach (pieces of a twentieth of R_near's width), for the band's vertices.
    let mut split = vec![SplitErrors::default(); BINS.len()];
    let normals = o.mesh.vertex_normals();
    let mut estimate = vec![[0.0f32; 3]; o.mesh.positions().len()];
    for (v, (x, n)) in o.mesh.positions().iter().zip(normals).enumerate() {
        let (x, n) = (x.as_dvec3(), n.as_dvec3());
        let nl = n.dot(l);
        let sums = gather.at(x);
        estimate[v] = std::array::from_fn(|c| (sums.far[c] + sums.blend(c)) as f32);
        let Some(bin) = BINS.iter().position(|&(a, b)| nl >= a && nl < b) else { continue };
        let e_x = lighting.transmitted(x, n);
        let b_mean = kernel::B_PER_SQRT_AREA * (sums.asum / sums.wsum1.max(1e-300)).sqrt();
        let exact = t.exitance[0][v];
        acc[bin].add(&sums, exact, e_x, dipoles, b_mean);
        if nl.abs() < 0.2 || (0.4..0.7).contains(&nl) {
            let exact_near = exact_near_part(&lighting, &o.mesh, dipoles, x, b_mean);
            split[bin].add(&sums, exact, exact_near);
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
    print_bins(&acc, &split);
}

/// What `reference::transmitted_irradiance` needs besides the point, held once so that the
/// brute-force near part can ask at any surface point.
struct Lighting<'a> {
    scene: &'a PreparedScene,
    occluders: &'a Bvh,
    /// The object's relative index of refraction.
    eta: f64,
    /// Shadow rays' offset from the surface.
    eps: f64,
}

impl Lighting<'_> {
    /// `E_t` at `p` with shading normal `n`.
    fn transmitted(&self, p: DVec3, n: DVec3) -> DVec3 {
        reference::transmitted_irradiance(self.scene, self.occluders, p, n, self.eta, self.eps).0
    }
}

/// The f64 twin of the vertex gather over the object's samples, with the experiment's
/// replacements (BLEND_K, UNIFORM_B, COMMON_R) read once from the environment.
struct Gather<'a> {
    /// Each sample with its splatted irradiance.
    samples: Vec<(&'a SamplePoint, &'a [f64; 3])>,
    dipoles: &'a [Dipole; 3],
    /// The blend's radius factor per channel, in units of `sqrt(dA)`.
    k: [f64; 3],
    /// Per sample and channel, the blend's squared radius `k^2 dA`.
    radius_sq: Vec<[f64; 3]>,
    /// UNIFORM_B: every sample's `b` from `mean_area_all`, the object's mean sample area.
    uniform_b: bool,
    mean_area_all: f64,
    /// COMMON_R: one blend radius per receiver from its local mean area.
    common_r: bool,
}

/// The gather's sums at one receiver.
struct Sums {
    /// The far kernel's sum, per channel.
    far: [f64; 3],
    /// The near energies blended by the weights in `wsum`, not yet divided by it.
    near: [f64; 3],
    wsum: [f64; 3],
    /// Sums of the renderer's near-blend weights times area, and of the weights alone: their
    /// ratio is the local mean area.
    asum: f64,
    wsum1: f64,
}

impl Sums {
    /// The blended near part of channel `c` (zero where no sample reaches).
    fn blend(&self, c: usize) -> f64 {
        if self.wsum[c] > 0.0 { self.near[c] / self.wsum[c] } else { 0.0 }
    }
}

impl<'a> Gather<'a> {
    fn new(o: &'a PreparedObject, irradiance: &'a [[f64; 3]], dipoles: &'a [Dipole; 3]) -> Self {
        let samples: Vec<_> = o.samples.iter().zip(irradiance).collect();
        // The blend's radius factor per channel: the renderer's (kernel::near_blend_radii), or
        // BLEND_K=kr,kg,kb to try others (1.5,1.5,1.5 is the single radius used before).
        let k: [f64; 3] = match std::env::var("BLEND_K") {
            Ok(v) => {
                let k: Vec<f64> = v.split(',').map(|x| x.parse().unwrap()).collect();
                [k[0], k[1], k[2]]
            }
            Err(_) => o.near_blend_radii(),
        };
        let uniform_b = std::env::var("UNIFORM_B").is_ok();
        let mean_area_all = o.samples.iter().map(|s| s.area).sum::<f64>() / o.samples.len() as f64;
        let radius_sq: Vec<[f64; 3]> = o.samples.iter().map(|s| k.map(|k| k * k * s.area)).collect();
        let common_r = std::env::var("COMMON_R").is_ok();
        Gather { samples, dipoles, k, radius_sq, uniform_b, mean_area_all, common_r }
    }

    /// The sums at receiver `x`: per-sample blend radii (or COMMON_R's one radius).
    fn at(&self, x: DVec3) -> Sums {
        let dipoles = self.dipoles;
        let (mut far, mut near, mut wsum, mut asum) = ([0.0; 3], [0.0; 3], [0.0; 3], 0.0);
        for ((s, e), rsq) in self.samples.iter().zip(&self.radius_sq) {
            let r = x.distance(s.position.as_dvec3());
            let b = kernel::B_PER_SQRT_AREA * if self.uniform_b { self.mean_area_all } else { s.area }.sqrt();
            asum += kernel::near_blend_weight(r, s.area, kernel::NEAR_BLEND_RADIUS) * s.area;
            for c in 0..3 {
                let t = if r * r < rsq[c] { 1.0 - r * r / rsq[c] } else { 0.0 };
                let w = t * t * t;
                wsum[c] += w;
                far[c] += e[c] * s.area * kernel::r_d_far(&dipoles[c], r, b);
                near[c] += w * e[c] * kernel::near_energy(&dipoles[c], b);
            }
        }
        let wsum1: f64 = self
            .samples
            .iter()
            .map(|(s, _)| {
                kernel::near_blend_weight(x.distance(s.position.as_dvec3()), s.area, kernel::NEAR_BLEND_RADIUS)
            })
            .sum();
        if self.common_r && wsum1 > 0.0 {
            (near, wsum) = self.common_radius_blend(x, asum / wsum1);
        }
        Sums { far, near, wsum, asum, wsum1 }
    }

    /// COMMON_R's near blend at `x`: one radius per channel, from the local mean area
    /// `a_local`; weights `A_i phi`. Returns the blended energies and the weights' sums.
    fn common_radius_blend(&self, x: DVec3, a_local: f64) -> ([f64; 3], [f64; 3]) {
        let (mut near, mut wsum) = ([0.0; 3], [0.0; 3]);
        for (s, e) in self.samples.iter() {
            let r = x.distance(s.position.as_dvec3());
            let b = kernel::B_PER_SQRT_AREA * s.area.sqrt();
            for c in 0..3 {
                let rsq = self.k[c] * self.k[c] * a_local;
                let t = if r * r < rsq { 1.0 - r * r / rsq } else { 0.0 };
                let w = s.area * t * t * t;
                wsum[c] += w;
                near[c] += w * e[c] * kernel::near_energy(&self.dipoles[c], b);
            }
        }
        (near, wsum)
    }
}

/// Per bin, summed relative errors against the truth, per channel.
#[derive(Clone, Default)]
struct BinErrors {
    /// Of the gather (far sum plus blend).
    gather: [f64; 3],
    /// Of the far sum plus the local near part `E_t(x) E_near`.
    far_local: [f64; 3],
    /// The blend's share of the truth.
    near_share: [f64; 3],
    /// The blend minus the local near part.
    blend_minus_local: [f64; 3],
    /// Vertices in the bin.
    n: usize,
}

impl BinErrors {
    /// Adds a vertex with exitance `exact` and transmitted irradiance `e_x`; unlit channels are
    /// skipped (no relative error), the vertex still counted.
    fn add(&mut self, sums: &Sums, exact: [f64; 3], e_x: DVec3, dipoles: &[Dipole; 3], b_mean: f64) {
        for c in 0..3 {
            if exact[c] <= 0.0 {
                continue;
            }
            let blend = sums.blend(c);
            let exact_near = e_x[c] * kernel::near_energy(&dipoles[c], b_mean);
            self.gather[c] += (sums.far[c] + blend - exact[c]) / exact[c];
            self.far_local[c] += (sums.far[c] + exact_near - exact[c]) / exact[c];
            self.near_share[c] += blend / exact[c];
            self.blend_minus_local[c] += (blend - exact_near) / exact[c];
        }
        self.n += 1;
    }
}

/// Per bin, summed relative errors of the gather's two parts against the exact near part.
#[derive(Clone, Default)]
struct SplitErrors {
    /// The far sum against the exact far part (truth minus exact near).
    far: [f64; 3],
    /// The blend against the exact near part.
    near: [f64; 3],
    /// Vertices in the bin.
    n: usize,
}

impl SplitErrors {
    fn add(&mut self, sums: &Sums, exact: [f64; 3], exact_near: [f64; 3]) {
        for c in 0..3 {
            if exact[c] <= 0.0 {
                continue;
            }
            let blend = sums.blend(c);
            // far sum against exact far (truth - exact near), blend against exact near
            self.far[c] += (sums.far[c] - (exact[c] - exact_near[c])) / exact[c];
            self.near[c] += (blend - exact_near[c]) / exact[c];
        }
        self.n += 1;
    }
}

/// The exact near part at `x`, integral `R_near(|x - y|; b_mean) E_t(y) dA(y)`, by brute force:
/// every triangle within reach (`8 ell`) cut into pieces a twentieth of `ell` across, with `E_t`
/// traced at each piece's centroid.
fn exact_near_part(lighting: &Lighting, mesh: &Mesh, dipoles: &[Dipole; 3], x: DVec3, b_mean: f64) -> [f64; 3] {
    let ell = (dipoles.iter().map(|d| d.z_v * d.z_v).fold(0.0, f64::max) + b_mean * b_mean).sqrt();
    let reach = 8.0 * ell;
    let mut exact_near = [0.0; 3];
    for tri in 0..mesh.triangles().len() {
        let [p0, p1, p2] = mesh.corners(tri);
        if x.distance(p0).min(x.distance(p1)).min(x.distance(p2)) > reach + p0.distance(p1).max(p1.distance(p2)) {
            continue;
        }
        let area = 0.5 * (p1 - p0).cross(p2 - p0).length();
        let m = ((p0.distance(p1).max(p1.distance(p2)).max(p2.distance(p0))) / (ell / 20.0)).ceil().max(1.0) as usize;
        let each = area / (m * m) as f64;
        let inv = 1.0 / m as f64;
        let mut piece = |u: f64, w: f64| {
            let bary = [1.0 - u - w, u, w];
            let y = p0 * bary[0] + p1 * bary[1] + p2 * bary[2];
            let r = x.distance(y);
            if r > reach {
                return;
            }
            let ny = mesh.normal_at(tri, bary).as_dvec3();
            let e = lighting.transmitted(y, ny);
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
    exact_near
}

/// The per-bin tables: the gather's errors, then (for the bins with brute-forced vertices) its
/// far sum and blend against the exact near part.
fn print_bins(acc: &[BinErrors], split: &[SplitErrors]) {
    for (bin, a) in BINS.iter().zip(acc) {
        let f = |v: [f64; 3]| mean_percent(v, a.n);
        println!(
            "[{:+.1},{:+.1}) n={:4}  gather {}  far+E_t(x)E_near {}  near share {}  blend-minus-local {}",
            bin.0,
            bin.1,
            a.n,
            f(a.gather),
            f(a.far_local),
            f(a.near_share),
            f(a.blend_minus_local)
        );
    }
    println!("split against the exact near part (brute force):");
    for (bin, sp) in BINS.iter().zip(split) {
        if sp.n == 0 {
            continue;
        }
        let f = |v: [f64; 3]| mean_percent(v, sp.n);
        println!(
            "[{:+.1},{:+.1}) n={:4}  far sum - exact far {}  blend - exact near {}",
            bin.0,
            bin.1,
            sp.n,
            f(sp.far),
            f(sp.near)
        );
    }
}

/// The mean of `n` summed relative errors per channel, as "r/g/b%".
fn mean_percent(sum: [f64; 3], n: usize) -> String {
    let m = sum.map(|v| 100.0 * v / n as f64);
    format!("{:+.2}/{:+.2}/{:+.2}%", m[0], m[1], m[2])
}

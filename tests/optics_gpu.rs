//! The GPU twin: `glsl/dipole_eval.comp` evaluates every function of `glsl/common/dipole.glsl`
//! in f32 over a grid of parameters (every preset, the hard cases, r from 0 to 1e3 diffusion
//! lengths, scales from micrometres to metres) on the validated test device (lavapipe), and each
//! value is compared with the f64 reference in `src/optics`.
//!
//! Criteria: every value finite; relative error <= 1e-4 wherever the reference is above 1e-30
//! of its peak over the same sweep (same material, scale and sample area; over r and angles)
//! and large enough to carry four digits in f32 (>= 1e-35, a thousand times f32's smallest
//! normal number); elsewhere the absolute error must stay below 1e-4 of that floor or of the
//! sweep's peak.

mod common;

use ash::vk;
use common::with_gpu;
use std::collections::HashMap;
use translucent::gpu::{Access, Binding, Buffer, BufferDesc, ComputePipeline, Named, memory_barrier};
use translucent::optics::fresnel::{self, fresnel_reflectance, fresnel_transmittance};
use translucent::optics::gpu::{DipoleEvalInput, DipoleEvalOutput};
use translucent::optics::kernel::{self, footprint_kernel, near_energy, r_d_far};
use translucent::optics::{Dipole, Material, presets};

const REL_TOLERANCE: f64 = 1e-4;
const PEAK_FRACTION: f64 = 1e-30;
const F32_FLOOR: f64 = 1e-35;

/// One material channel at one scale: the f32 inputs it is evaluated with.
struct Case {
    label: String,
    sigma_a: f32,
    sigma_s_prime: f32,
    eta: f32,
    mm_per_unit: f32,
}

fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    // Every preset, every channel, at 1 mm per unit (its own eta).
    for m in presets::all() {
        for c in 0..3 {
            out.push(Case {
                label: format!("{} [{c}]", m.name),
                sigma_a: m.sigma_a[c] as f32,
                sigma_s_prime: m.sigma_s_prime[c] as f32,
                eta: m.eta as f32,
                mm_per_unit: 1.0,
            });
        }
    }
    // Hard cases: no absorption, sigma_s' from 1e-6 to 1e4 per mm, eta = 1 and eta < 1,
    // scales from micrometres to metres.
    for sigma_a in [0.0f32, 1e-4, 1e-2, 1.0, 1e2] {
        for sigma_s_prime in [1e-6f32, 1e-4, 1e-2, 1.0, 1e2, 1e4] {
            for eta in [fresnel::ETA_MIN as f32, 0.75, 1.0, 1.3, 1.5, fresnel::ETA_MAX as f32] {
                for mm_per_unit in [1e-3f32, 1.0, 1e3] {
                    out.push(Case {
                        label: format!(
                            "sigma_a {sigma_a:e} sigma_s' {sigma_s_prime:e} eta {eta} scale {mm_per_unit:e}"
                        ),
                        sigma_a,
                        sigma_s_prime,
                        eta,
                        mm_per_unit,
                    });
                }
            }
        }
    }
    out
}

/// The reference dipole for a case, from the very f32 inputs the GPU sees.
fn dipole(case: &Case) -> Dipole {
    let scale = case.mm_per_unit as f64;
    Dipole::new(case.sigma_a as f64 * scale, case.sigma_s_prime as f64 * scale, case.eta as f64, 0)
        .unwrap_or_else(|e| panic!("{}: {e}", case.label))
}

/// The records for one case: sample areas from far below to far above z_r^2 and the diffusion
/// length squared; distances 0, fractions of z_r, and up to 1e3 diffusion lengths (1e3 z_v when
/// there is no absorption); a few angle pairs. Returns (records, sweep id per record).
fn records(case: &Case, d: &Dipole, t_eta: f32) -> Vec<(DipoleEvalInput, usize)> {
    let length = if d.sigma_tr > 0.0 { d.diffusion_length() } else { d.z_v };
    let mut distances = vec![0.0];
    distances.extend([1e-4, 1e-2, 0.1, 0.5, 1.0, 3.0, 10.0].map(|f| f * d.z_r));
    distances.extend([1e-2, 0.3, 1.0, 2.0, 5.0, 10.0, 30.0, 100.0, 300.0, 1e3].map(|f| f * length));
    let mut areas: Vec<f64> = [1e-6, 1e-2, 1.0, 1e2, 1e6].map(|f| f * d.z_r * d.z_r).to_vec();
    areas.extend([1e-2, 1.0, 1e2].map(|f| f * length * length));
    let angles = [(1.0f32, 1.0f32), (0.7, 0.2), (0.05, 0.0)];
    let mut out = Vec::new();
    for (a, &area) in areas.iter().enumerate() {
        for &r in &distances {
            for &(cos_theta_i, cos_theta_o) in &angles {
                let input = DipoleEvalInput {
                    sigma_a: case.sigma_a,
                    sigma_s_prime: case.sigma_s_prime,
                    eta: case.eta,
                    mm_per_unit: case.mm_per_unit,
                    r: r as f32,
                    area: area as f32,
                    cos_theta_i,
                    cos_theta_o,
                    t_eta,
                    _pad: [0.0; 3],
                };
                out.push((input, a));
            }
        }
    }
    out
}

/// The f64 reference of every output field, from the f32 input widened to f64.
fn reference(d: &Dipole, p: &DipoleEvalInput) -> [f64; 18] {
    let (r, area) = (p.r as f64, p.area as f64);
    let b = kernel::B_PER_SQRT_AREA * area.sqrt();
    let (cos_i, cos_o) = (p.cos_theta_i as f64, p.cos_theta_o as f64);
    [
        d.sigma_t_prime,
        d.alpha_prime,
        d.sigma_tr,
        d.F_dr,
        d.A,
        d.z_r,
        d.z_v,
        d.r_d(r),
        d.r_d_total(),
        d.r_d_disk(r),
        footprint_kernel(d, r, area),
        near_energy(d, b),
        r_d_far(d, r, b),
        kernel::r_d_far_cluster(d, r, b, 0.3 * r * r, 0.1 * r * r),
        fresnel_reflectance(cos_i, d.eta),
        fresnel_transmittance(cos_o, d.eta),
        d.s_d(r, cos_i, cos_o, p.t_eta as f64),
        kernel::near_kept_at_edge(d, b, r),
    ]
}

fn fields(o: &DipoleEvalOutput) -> [f32; 18] {
    [
        o.sigma_t_prime,
        o.alpha_prime,
        o.sigma_tr,
        o.F_dr,
        o.A,
        o.z_r,
        o.z_v,
        o.r_d,
        o.r_d_total,
        o.r_d_disk,
        o.kernel,
        o.near_energy,
        o.r_d_far,
        o.r_d_far_cluster,
        o.fresnel_r,
        o.fresnel_t,
        o.s_d,
        o.near_kept_edge,
    ]
}

const NAMES: [&str; 18] = [
    "sigma_t'",
    "alpha'",
    "sigma_tr",
    "F_dr",
    "A",
    "z_r",
    "z_v",
    "R_d",
    "R_d,total",
    "disk P(r)",
    "kernel",
    "E_near",
    "R_far",
    "R_far cluster",
    "F_r",
    "F_t",
    "S_d",
    "E_near kept at an edge",
];

fn run_on_gpu(inputs: &[DipoleEvalInput]) -> Vec<DipoleEvalOutput> {
    eval_on_gpu("dipole_eval.comp", inputs)
}

/// One invocation of `shader` (under glsl/, bindings `Inputs` and `Outputs`, push: the count) per
/// input record, read back.
fn eval_on_gpu<I: bytemuck::Pod, O: bytemuck::Pod>(shader: &str, inputs: &[I]) -> Vec<O> {
    with_gpu(|gpu| {
        let count = inputs.len() as u32;
        let pipeline = ComputePipeline::new(gpu, shader).expect("evaluation pipeline");
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let src = Buffer::from_slice(gpu, "evaluation inputs", inputs, usage).expect("input buffer");
        let bytes = (inputs.len() * std::mem::size_of::<O>()) as u64;
        let dst = Buffer::new(gpu, &BufferDesc::readback("evaluation outputs", bytes, usage)).expect("output buffer");
        let set = pipeline
            .descriptor_set(&[
                Named { name: "Inputs", binding: Binding::Buffer(&src) },
                Named { name: "Outputs", binding: Binding::Buffer(&dst) },
            ])
            .expect("descriptor set");
        gpu.one_shot(shader, |cmd| {
            pipeline.dispatch(cmd, &set, &count, [count, 1, 1]);
            memory_barrier(gpu.device(), cmd, &[Access::ComputeWrite], &[Access::HostRead]);
        })
        .expect("dispatch");
        dst.read().expect("readback")
    })
}

#[test]
fn glsl_twin_matches_f64_reference() {
    // Build the records and their references.
    let mut inputs = Vec::new();
    let mut refs = Vec::new();
    let mut sweep = Vec::new(); // (case index, area index) per record
    let cases = cases();
    for (ci, case) in cases.iter().enumerate() {
        let d = dipole(case);
        let t_eta = Material::new("t", [0.0; 3], [1.0; 3], case.eta as f64).unwrap().diffuse_transmittance() as f32;
        for (input, a) in records(case, &d, t_eta) {
            refs.push(reference(&d, &input));
            inputs.push(input);
            sweep.push((ci, a));
        }
    }
    let outputs = run_on_gpu(&inputs);
    assert_eq!(outputs.len(), inputs.len());

    // Peak of each field over its sweep.
    let mut peaks: HashMap<(usize, usize, usize), f64> = HashMap::new();
    for (i, r) in refs.iter().enumerate() {
        for (f, &v) in r.iter().enumerate() {
            let peak = peaks.entry((sweep[i].0, sweep[i].1, f)).or_insert(0.0);
            *peak = peak.max(v.abs());
        }
    }

    let mut worst: Vec<(f64, String)> = vec![(0.0, String::new()); 18];
    let (mut compared, mut floor_only, mut failures) = (0usize, 0usize, Vec::new());
    for (i, (out, r)) in outputs.iter().zip(&refs).enumerate() {
        let p = &inputs[i];
        let case = &cases[sweep[i].0];
        for (f, (&g, &want)) in fields(out).iter().zip(r).enumerate() {
            let at = format!(
                "{} {} at r = {:e}, dA = {:e}, cos {}/{}",
                NAMES[f], case.label, p.r, p.area, p.cos_theta_i, p.cos_theta_o
            );
            assert!(g.is_finite(), "{at}: GPU gave {g}");
            assert!(want.is_finite(), "{at}: reference gave {want}");
            let g = g as f64;
            let peak = peaks[&(sweep[i].0, sweep[i].1, f)];
            if want.abs() > PEAK_FRACTION * peak && want.abs() >= F32_FLOOR {
                let e = (g - want).abs() / want.abs();
                compared += 1;
                if e > worst[f].0 {
                    worst[f] = (e, at.clone());
                }
                if e > REL_TOLERANCE {
                    failures.push(format!("{at}: GPU {g:e} vs f64 {want:e} (relative {e:.2e})"));
                }
            } else {
                floor_only += 1;
                // f32 flushes what falls a hundred times below its smallest normal to zero (an
                // exponential near e^-100 times a large polynomial): that much is allowed too.
                let allowed = (REL_TOLERANCE * F32_FLOOR.max(PEAK_FRACTION * peak)).max(1e2 * f32::MIN_POSITIVE as f64);
                if (g - want).abs() > allowed {
                    failures.push(format!("{at}: GPU {g:e} vs f64 {want:e} below the comparison floor"));
                }
            }
        }
    }
    println!(
        "{} records ({} cases): {compared} values compared relatively, {floor_only} below the floor",
        inputs.len(),
        cases.len()
    );
    println!("worst relative error per function:");
    for (f, (e, at)) in worst.iter().enumerate() {
        println!("  {:<10} {e:9.2e}  {at}", NAMES[f]);
    }
    // Not vacuous: the bulk of the grid (seven in eight values; the far kernels' tails at large r
    // fall below the floor) is compared relatively.
    assert!(compared > 7 * floor_only, "only {compared} of {} values were compared", compared + floor_only);
    let mut by_field: HashMap<&str, usize> = HashMap::new();
    for f in &failures {
        *by_field.entry(NAMES.iter().filter(|n| f.starts_with(*n)).max_by_key(|n| n.len()).unwrap()).or_default() += 1;
    }
    assert!(
        failures.is_empty(),
        "{} mismatches ({by_field:?}), first ones:\n{}",
        failures.len(),
        failures[..failures.len().min(30)].join("\n")
    );
}

/// `glsl/common/single_scatter.glsl` against `optics::single_scatter` (issue 26, part 5): the
/// single-scattering reflectance, the Henyey-Greenstein phase function and the refracted cosine
/// over albedos 0.001 to 0.999, `g` from -0.5 to 0.8, `eta` from 1/3 to 3 and incidence cosines
/// from grazing to normal. Every value finite, each within 1e-4 relative of the f64 reference
/// (the same 16 x 16 Gauss-Legendre rule, in f32) where that is above 1e-30.
#[test]
fn single_scattering_glsl_twin_matches_f64_reference() {
    use translucent::optics::single_scatter::{henyey_greenstein, reflectance, refracted_cosine};
    let mut inputs: Vec<[f32; 4]> = Vec::new();
    for albedo in [0.001f32, 0.02, 0.3, 0.747, 0.999] {
        for g in [-0.5f32, 0.0, 0.3, 0.8] {
            for eta in [fresnel::ETA_MIN as f32, 0.75, 1.0, 1.3, 1.5, fresnel::ETA_MAX as f32] {
                for cos in [1.0f32, 0.8, 0.5, 0.2, 0.05, 0.001] {
                    inputs.push([albedo, g, eta, cos]);
                }
            }
        }
    }
    let outputs: Vec<[f32; 4]> = eval_on_gpu("single_scatter_eval.comp", &inputs);
    let mut worst = [0.0f64; 3];
    for (p, o) in inputs.iter().zip(&outputs) {
        let [albedo, g, eta, cos] = p.map(f64::from);
        let want =
            [reflectance(albedo, g, eta, cos), henyey_greenstein(cos, g), refracted_cosine(cos, eta).unwrap_or(0.0)];
        for f in 0..3 {
            let got = f64::from(o[f]);
            assert!(got.is_finite(), "field {f} at {p:?}: {got}");
            if want[f] > 1e-30 {
                let e = (got - want[f]).abs() / want[f];
                worst[f] = worst[f].max(e);
                assert!(e <= 1e-4, "field {f} at {p:?}: GPU {got:e} vs f64 {:e} (relative {e:.2e})", want[f]);
            } else {
                assert!(got.abs() <= 1e-30, "field {f} at {p:?}: GPU {got:e}, f64 0");
            }
        }
    }
    eprintln!(
        "single scattering twin: worst relative error R1 {:.2e}, phase {:.2e}, cosine {:.2e}",
        worst[0], worst[1], worst[2]
    );
}

/// The directional dipole twin's cases (see its test): per case the GPU record (the model's
/// coefficients rounded to f32, then x_i, n_i, w_12, x_o, n_o) and the f64 model on the same
/// coefficients.
fn directional_records() -> (Vec<[[f32; 4]; 7]>, Vec<translucent::optics::directional_dipole::DirectionalDipole>) {
    use glam::DVec3;
    use translucent::optics::directional_dipole::{Diffusion, DirectionalDipole, Strength, refract_in};
    let mut records: Vec<[[f32; 4]; 7]> = Vec::new();
    let mut models: Vec<DirectionalDipole> = Vec::new();
    let f = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
    for name in ["marble", "ketchup", "skin1"] {
        let dipoles = Material::preset(name).unwrap().dipoles(1.0).unwrap();
        for d in &dipoles {
            for (diffusion, strength) in [
                (Diffusion::Grosjean, Strength::Paper),
                (Diffusion::Classical, Strength::Paper),
                (Diffusion::Grosjean, Strength::ReducedAlbedo),
            ] {
                let m = DirectionalDipole::with_options(d, diffusion, strength);
                // The model as the GPU sees it: every coefficient rounded to f32.
                let r32 = |v: f64| f64::from(v as f32);
                let m = DirectionalDipole {
                    D: r32(m.D),
                    sigma_tr: r32(m.sigma_tr),
                    d_e: r32(m.d_e),
                    A: r32(m.A),
                    C_phi: r32(m.C_phi),
                    C_E: r32(m.C_E),
                    sigma_t_prime: r32(m.sigma_t_prime),
                    strength: r32(m.strength),
                    ..m
                };
                for radius in [2.0, 10.0, f64::INFINITY] {
                    for cos_in in [1.0f64, 0.7, 0.3, 0.05] {
                        for distance in [0.01f64, 0.1, 0.5, 2.0, 8.0] {
                            for azimuth in [0.0f64, 1.0, 2.2, 3.1] {
                                let (x_i, n_i) = (DVec3::new(0.0, 0.0, 0.0), DVec3::Z);
                                let w_in = DVec3::new((1.0 - cos_in * cos_in).sqrt(), 0.0, cos_in);
                                let w_12 = refract_in(w_in, n_i, d.eta).unwrap();
                                // The exit point `distance` away along the surface (a great circle
                                // on the sphere), in the direction `azimuth` from the plane of
                                // incidence.
                                let dir = DVec3::new(azimuth.cos(), azimuth.sin(), 0.0);
                                let (x_o, n_o) = if radius.is_finite() {
                                    let a = distance / radius;
                                    let n = (DVec3::Z * a.cos() + dir * a.sin()).normalize();
                                    (n * radius - DVec3::Z * radius, n)
                                } else {
                                    (dir * distance, DVec3::Z)
                                };
                                let a = [m.D, m.sigma_tr, m.d_e, m.A].map(|v| v as f32);
                                let c = [m.C_phi, m.C_E, m.sigma_t_prime, m.strength].map(|v| v as f32);
                                records.push([a, c, f(x_i), f(n_i), f(w_12), f(x_o), f(n_o)]);
                                models.push(m);
                            }
                        }
                    }
                }
            }
        }
    }
    (records, models)
}

/// `glsl/common/directional_dipole.glsl` against `optics::directional_dipole` (issue 26): the
/// exitance per entering flux and its real and virtual source terms over marble, ketchup and
/// skin, both diffusion coefficients and both source strengths, entry points on a plane and on
/// spheres of radius 2 and 10 mm, incidence from normal to grazing, exit points from 0.01 to
/// 8 mm away in every direction. Every value finite; the exitance and each source term within
/// 1e-4 of the two terms' absolute sum of the f64 (evaluated on the same f32 inputs): the
/// exitance is their difference and each term a difference of its fluence and flux parts, so a
/// plain relative bound fails where they cancel (1.65e-4 on a virtual term 1e-3 of the real one).
#[test]
fn directional_dipole_glsl_twin_matches_f64_reference() {
    use glam::DVec3;
    let (records, models) = directional_records();
    let outputs: Vec<[f32; 4]> = eval_on_gpu("directional_dipole_eval.comp", &records);
    let v = |p: [f32; 4]| DVec3::new(p[0].into(), p[1].into(), p[2].into());
    let (mut worst, mut worst_exitance) = ([0.0f64; 2], 0.0f64);
    for ((r, o), m) in records.iter().zip(&outputs).zip(&models) {
        let (x_i, n_i, w_12, x_o, n_o) = (v(r[2]), v(r[3]), v(r[4]), v(r[5]), v(r[6]));
        let (real, virtual_) = m.sources(x_i, n_i, w_12, x_o, n_o);
        let exitance = m.exitance_per_flux(x_i, n_i, w_12, x_o, n_o);
        assert!(o.iter().all(|x| x.is_finite()), "{o:?} at {r:?}");
        // Each term is a difference too (fluence and flux parts), so f32 is held to the pair's
        // magnitude; plainly relative where a term is at least a tenth of it.
        let scale = real.abs() + virtual_.abs();
        if scale <= 1e-30 {
            continue;
        }
        for (k, want) in [real, virtual_].into_iter().enumerate() {
            let got = f64::from(o[k + 1]);
            let e = (got - want).abs() / scale;
            assert!(e <= 1e-4, "term {k} at {r:?}: GPU {got:e} vs f64 {want:e} ({e:.2e} of the terms)");
            if want.abs() >= 0.1 * scale {
                worst[k] = worst[k].max((got - want).abs() / want.abs());
            }
        }
        let e = (f64::from(o[0]) - exitance).abs() / (m.strength * scale);
        worst_exitance = worst_exitance.max(e);
        assert!(e <= 1e-4, "exitance at {r:?}: GPU {:e} vs f64 {exitance:e} ({e:.2e} of the terms)", o[0]);
    }
    eprintln!(
        "directional dipole twin, {} records: worst relative error real {:.2e}, virtual {:.2e} (where at least a tenth \
         of the terms' sum); exitance {:.2e} of the terms' sum",
        records.len(),
        worst[0],
        worst[1],
        worst_exitance
    );
}

/// `glsl/common/beam_single.glsl` against `optics::beam_single` (issue 26): single scattering
/// between two surface points, for dark and bright media, `g` 0 and 0.5, incidence from normal
/// to grazing, receivers from a thousandth of a mean free path to eight mean free paths away in
/// every direction, on flat and tilted tangent planes. Every value finite, each within 2e-3
/// relative of the f64 reference where that is at least 1e-6 of the case's largest value.
#[test]
fn beam_single_scattering_glsl_twin_matches_f64_reference() {
    use glam::DVec3;
    use translucent::optics::beam_single::BeamSingle;
    use translucent::optics::directional_dipole::refract_in;
    let mut records: Vec<[[f32; 4]; 5]> = Vec::new();
    let mut cases = Vec::new();
    for (albedo, sigma_t, g, eta) in [(0.067, 1.04, 0.0, 1.3), (0.02, 1.48, 0.0, 1.3), (0.99, 2.2, 0.5, 1.5)] {
        let m = BeamSingle { sigma_s: albedo * sigma_t, sigma_t, g, eta };
        for cos_i in [1.0f64, 0.6, 0.1] {
            let w_in = DVec3::new((1.0 - cos_i * cos_i).sqrt(), 0.0, cos_i);
            let w_12 = refract_in(w_in, DVec3::Z, eta).unwrap();
            for rho in [1e-3, 0.05, 0.3, 1.0, 3.0, 8.0] {
                for alpha in [0.0f64, 1.3, 2.7, 3.6, 5.0] {
                    let x_o = DVec3::new(alpha.cos(), alpha.sin(), 0.0) * rho / sigma_t;
                    for n_o in [DVec3::Z, DVec3::new(0.3, -0.2, 1.0).normalize()] {
                        let f = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
                        let coefficients = [m.sigma_s as f32, sigma_t as f32, g as f32, eta as f32];
                        records.push([coefficients, f(DVec3::ZERO), f(w_12), f(x_o), f(n_o)]);
                        // The f64 on the f32-rounded inputs.
                        let r = |v: DVec3| v.as_vec3().as_dvec3();
                        let m32 = BeamSingle {
                            sigma_s: f64::from(coefficients[0]),
                            sigma_t: f64::from(coefficients[1]),
                            g: f64::from(coefficients[2]),
                            eta: f64::from(coefficients[3]),
                        };
                        cases.push(m32.exitance_per_flux(DVec3::ZERO, r(w_12), r(x_o), r(n_o)));
                    }
                }
            }
        }
    }
    let outputs: Vec<[f32; 4]> = eval_on_gpu("beam_single_eval.comp", &records);
    let largest = cases.iter().fold(0.0f64, |a, b| a.max(*b));
    let mut worst = 0.0f64;
    for ((record, want), got) in records.iter().zip(&cases).zip(&outputs) {
        let got = f64::from(got[0]);
        assert!(got.is_finite(), "{record:?}: {got}");
        if *want >= 1e-6 * largest {
            let e = (got - want).abs() / want;
            worst = worst.max(e);
            assert!(e <= 2e-3, "{record:?}: GPU {got:e} vs f64 {want:e} (relative {e:.2e})");
        }
    }
    eprintln!("beam single-scattering twin, {} records: worst relative error {worst:.2e}", records.len());
}

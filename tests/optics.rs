//! CPU (f64) tests of the dipole model: closed forms against numerical integration, energy
//! bounds, Fresnel limits, the BSSRDF normalization, the near-field kernel on a lattice, the
//! std430 records, presets and bad input.
//!
//! Run `cargo test --test optics -- --nocapture` to see the tables the tests print.

mod common;

use rand::{RngExt, SeedableRng};
use rayon::prelude::*;
use std::f64::consts::PI;
use translucent::optics::fresnel::{self, fresnel_moment1, fresnel_reflectance, fresnel_transmittance};
use translucent::optics::gpu::{DipoleChannelGpu, DipoleEvalInput, DipoleEvalOutput};
use translucent::optics::kernel::{self, footprint_kernel, near_energy, point_kernel};
use translucent::optics::presets::{self, JENSEN_2001, NARASIMHAN_2006};
use translucent::optics::{Dipole, Material, OpticsError};

// ---------------------------------------------------------------- helpers

/// Integral of `f(r) 2 pi r dr` over `[lo, hi]` (lo > 0) by composite Simpson in `t = ln r`,
/// independent of the library's quadratures. `steps` is rounded up to even.
fn radial_integral(f: impl Fn(f64) -> f64, lo: f64, hi: f64, steps: usize) -> f64 {
    let n = steps + steps % 2;
    let (a, b) = (lo.ln(), hi.ln());
    let h = (b - a) / n as f64;
    let g = |t: f64| {
        let r = t.exp();
        f(r) * 2.0 * PI * r * r // dr = r dt
    };
    let mut sum = g(a) + g(b);
    for i in 1..n {
        sum += if i % 2 == 1 { 4.0 } else { 2.0 } * g(a + i as f64 * h);
    }
    sum * h / 3.0
}

/// Every channel of every preset with scattering and absorption, at 1 mm per unit.
fn preset_dipoles() -> Vec<(String, Dipole)> {
    let mut out = Vec::new();
    for m in presets::all() {
        let ds = m.material().dipoles(1.0).unwrap();
        for (c, d) in ds.into_iter().enumerate() {
            out.push((format!("{} [{}]", m.name, c), d));
        }
    }
    out
}

fn rel(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { (a - b).abs() / b.abs().max(a.abs()) }
}

// ---------------------------------------------------------------- the dipole profile

#[test]
fn the_profile_radius_is_the_rms_radius_of_r_d_by_quadrature() {
    let mut checked = 0;
    for (name, d) in preset_dipoles() {
        if d.sigma_a == 0.0 || d.alpha_prime == 0.0 {
            assert!(d.sigma_a > 0.0 || d.profile_radius().is_infinite(), "{name}");
            continue;
        }
        let hi = d.z_v + 80.0 * d.diffusion_length();
        let moment = radial_integral(|r| r * r * d.r_d(r), 1e-9 * d.z_r, hi, 40_000);
        let numeric = (moment / d.r_d_total()).sqrt();
        assert!(rel(numeric, d.profile_radius()) < 1e-6, "{name}: numeric {numeric} vs {}", d.profile_radius());
        // Wider than the real source's depth, and finite.
        assert!(d.profile_radius() > d.z_r * 0.5 && d.profile_radius().is_finite(), "{name}");
        checked += 1;
    }
    assert!(checked > 100);
}

#[test]
fn r_d_derivatives_match_central_differences() {
    for (name, d) in preset_dipoles() {
        // (No absorption makes the diffusion length infinite: that distance is skipped.)
        for r in [0.0, 0.3 * d.z_r, d.z_r, 2.0 * d.z_v, 3.0 / d.sigma_tr].into_iter().filter(|r| r.is_finite()) {
            let (g, g1, g2) = d.r_d_derivatives(r * r);
            assert!(rel(g, d.r_d(r)) < 1e-12, "{name} r={r}: R_d");
            let h = 1e-4 * (r + d.z_r);
            let f = |r: f64| d.r_d(r);
            let first = (f(r + h) - f((r - h).abs())) / (2.0 * h);
            let second = (f(r + h) - 2.0 * f(r) + f((r - h).abs())) / (h * h);
            if r > 0.0 {
                assert!(rel(g1 * r, first) < 1e-5, "{name} r={r}: R_d' {} vs {first}", g1 * r);
            }
            assert!(rel(g2, second) < 1e-4, "{name} r={r}: R_d'' {g2} vs {second}");
        }
    }
}

#[test]
fn total_reflectance_equals_numerical_integral_of_r_d() {
    let mut worst = 0.0f64;
    let mut checked = 0;
    for (name, d) in preset_dipoles() {
        if d.sigma_a == 0.0 || d.alpha_prime == 0.0 {
            continue; // no finite diffusion length / nothing reflected: covered elsewhere
        }
        // R_d falls as e^(-sigma_tr r): 60 diffusion lengths past z_v leave < 1e-20 of it.
        let hi = d.z_v + 60.0 * d.diffusion_length();
        let numeric = radial_integral(|r| d.r_d(r), 1e-9 * d.z_r, hi, 40_000);
        let e = rel(numeric, d.r_d_total());
        assert!(e < 1e-6, "{name}: numeric {numeric} vs closed form {}", d.r_d_total());
        worst = worst.max(e);
        checked += 1;
    }
    println!("closed-form R_d,total vs Simpson over r, {checked} channels: worst relative {worst:.1e}");
    assert!(checked > 100);
}

#[test]
fn disk_integral_matches_numerics_and_tends_to_total() {
    for name in ["marble", "ketchup", "skin1", "espresso", "cream"] {
        for d in Material::preset(name).unwrap().dipoles(1.0).unwrap() {
            let l = d.diffusion_length();
            let mut previous = 0.0;
            let mut radii = [1e-4 * d.z_r, 0.1 * d.z_r, d.z_r, l, 3.0 * l, 10.0 * l];
            radii.sort_by(f64::total_cmp);
            for radius in radii {
                let numeric = radial_integral(|r| d.r_d(r), 1e-10 * d.z_r, radius, 40_000);
                let exact = d.r_d_disk(radius);
                // Below 1e-10 z_r the disk holds ~1e-20 of R_d(0) pi z_r^2: negligible.
                assert!(rel(exact, numeric) < 1e-8, "{name} R={radius}: {exact} vs {numeric}");
                assert!(exact > previous && exact <= d.r_d_total() * (1.0 + 1e-12));
                previous = exact;
                // Ring = difference of disks, and what lies outside = total - disk.
                assert!(rel(d.r_d_ring(0.5 * radius, radius), exact - d.r_d_disk(0.5 * radius)) < 1e-9);
                assert!(rel(d.r_d_outside(radius), d.r_d_total() - exact) < 1e-6);
            }
            let far = d.r_d_disk(d.z_v + 80.0 * l);
            assert!(rel(far, d.r_d_total()) < 1e-12, "{name}: P(inf) {far} vs {}", d.r_d_total());
        }
    }
}

#[test]
fn thin_rings_and_tiny_disks_do_not_cancel() {
    // A disk 1e-6 z_r across holds R_d(0) pi R^2 to first order; the naive difference
    // e^(-s z) - z e^(-s d)/d would have lost every digit.
    let d = Material::preset("marble").unwrap().dipoles(1.0).unwrap()[0];
    for f in [1e-3, 1e-5, 1e-7] {
        let radius = f * d.z_r;
        let approx = d.r_d(0.0) * PI * radius * radius;
        assert!(rel(d.r_d_disk(radius), approx) < 3.0 * f, "R = {f} z_r");
        let (r, dr) = (2.0 * d.z_r, f * d.z_r);
        let approx_ring = d.r_d(r + 0.5 * dr) * 2.0 * PI * (r + 0.5 * dr) * dr;
        assert!(rel(d.r_d_ring(r, r + dr), approx_ring) < f, "ring dr = {f} z_r");
    }
}

#[test]
fn r_d_decreases_monotonically_and_stays_finite() {
    for (name, d) in preset_dipoles() {
        let mut previous = f64::INFINITY;
        for i in 0..=400 {
            let r = if i == 0 { 0.0 } else { d.z_r * 10f64.powf(-4.0 + i as f64 * 0.02) };
            let v = d.r_d(r);
            assert!(v.is_finite() && v >= 0.0, "{name}: R_d({r}) = {v}");
            assert!(v <= previous, "{name}: R_d rises at r = {r}: {v} > {previous}");
            previous = v;
        }
    }
}

#[test]
fn energy_bounds_hold_over_random_parameters() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(0x7a55_1d0e);
    let mut max_total = 0.0f64;
    for _ in 0..20_000 {
        let log_uniform =
            |rng: &mut rand_pcg::Pcg64, lo: f64, hi: f64| 10f64.powf(rng.random_range(lo.log10()..hi.log10()));
        let sigma_a = if rng.random_range(0..8) == 0 { 0.0 } else { log_uniform(&mut rng, 1e-6, 1e4) };
        let sigma_s_prime = if rng.random_range(0..16) == 0 { 0.0 } else { log_uniform(&mut rng, 1e-6, 1e4) };
        if sigma_a + sigma_s_prime == 0.0 {
            continue;
        }
        let eta = rng.random_range(fresnel::ETA_MIN..=fresnel::ETA_MAX);
        let d = Dipole::new(sigma_a, sigma_s_prime, eta, 0).unwrap();
        let total = d.r_d_total();
        let ctx = format!("sigma_a {sigma_a} sigma_s' {sigma_s_prime} eta {eta}");
        assert!((0.0..=1.0).contains(&total), "{ctx}: total {total}");
        assert!(total <= d.alpha_prime + 1e-15, "{ctx}: reflects more than it scatters");
        // The kernel pieces stay within the same bounds.
        let area = log_uniform(&mut rng, 1e-6, 1e6) * d.z_r * d.z_r;
        let b = kernel::B_PER_SQRT_AREA * area.sqrt();
        let e_near = near_energy(&d, b);
        assert!(e_near >= 0.0 && e_near <= total * (1.0 + 1e-9), "{ctx}: E_near {e_near} total {total}");
        let r = log_uniform(&mut rng, 1e-6, 1e6) * d.z_r;
        let k = footprint_kernel(&d, r, area);
        assert!(k.is_finite() && k >= 0.0, "{ctx}: K({r}, {area}) = {k}");
        max_total = max_total.max(total);
    }
    println!("20000 random parameter sets: 0 <= R_d,total <= 1, max {max_total:.6}");
}

#[test]
fn no_absorption_reflects_exactly_everything_it_scatters() {
    for sigma_s_prime in [1e-6, 1e-2, 1.0, 11.6, 1e4] {
        for eta in [fresnel::ETA_MIN, 0.8, 1.0, 1.3, 1.5, fresnel::ETA_MAX] {
            let d = Dipole::new(0.0, sigma_s_prime, eta, 0).unwrap();
            assert_eq!(d.sigma_tr, 0.0);
            assert_eq!(d.alpha_prime, 1.0);
            assert_eq!(d.r_d_total(), 1.0, "sigma_s' {sigma_s_prime} eta {eta}");
            assert!(d.diffusion_length().is_infinite());
            assert!(d.r_d(0.0).is_finite() && d.r_d(1e12).is_finite());
        }
    }
    for d in Material::preset("spectralon").unwrap().dipoles(1.0).unwrap() {
        assert_eq!(d.r_d_total(), 1.0);
    }
}

#[test]
fn derived_quantities_follow_their_definitions() {
    // Cross-check the stored fields against the definitions written the other way round.
    for (name, d) in preset_dipoles() {
        assert!(rel(d.sigma_tr, (d.sigma_a / d.D).sqrt()) < 1e-12, "{name}: sigma_tr");
        assert!(rel(d.z_v, d.z_r + 4.0 * d.A * d.D) < 1e-12, "{name}: z_v");
        assert!(rel(d.alpha_prime + d.one_minus_alpha_prime, 1.0) < 1e-15, "{name}");
        assert!(rel(d.A, (1.0 + d.F_dr) / (1.0 - d.F_dr)) < 1e-15, "{name}");
        assert_eq!(d.mean_free_path(), d.z_r);
    }
    // Both F_dr fits stay in [0, 1) over the accepted range and nearly agree at eta = 1.
    for i in 0..=1000 {
        let eta = fresnel::ETA_MIN + (fresnel::ETA_MAX - fresnel::ETA_MIN) * i as f64 / 1000.0;
        let f = fresnel::F_dr(eta);
        assert!((0.0..1.0).contains(&f), "F_dr({eta}) = {f}");
    }
    assert!((fresnel::F_dr(1.0) - fresnel::F_dr(1.0 - 1e-12)).abs() < 1e-3);
    // The expanded form evaluated everywhere is the published polynomial.
    for i in 0..=10_000 {
        let eta = fresnel::ETA_MIN + (fresnel::ETA_MAX - fresnel::ETA_MIN) * i as f64 / 10_000.0;
        let (a, b) = (fresnel::F_dr(eta), fresnel::F_dr_as_published(eta));
        assert!((a - b).abs() < 1e-13, "F_dr({eta}): {a} vs published {b}");
    }
    // Scene scale: coefficients per unit scale with mm per unit; lengths inversely.
    let m = Material::preset("skin1").unwrap();
    let (mm, um) = (m.dipoles(1.0).unwrap(), m.dipoles(1e-3).unwrap());
    for c in 0..3 {
        assert!(rel(um[c].z_r, mm[c].z_r * 1e3) < 1e-12);
        assert!(rel(um[c].r_d_total(), mm[c].r_d_total()) < 1e-12);
    }
}

// ---------------------------------------------------------------- Fresnel and the BSSRDF

#[test]
fn fresnel_limits() {
    // eta = 1: no interface, everything is transmitted, even at grazing incidence.
    for i in 0..=1000 {
        let c = i as f64 / 1000.0;
        assert_eq!(fresnel_transmittance(c, 1.0), 1.0);
    }
    assert_eq!(fresnel_moment1(1.0), 0.0);
    for eta in [1.0 / 3.0, 0.5, 1.0 / 1.3, 0.9_f64] {
        // Total internal reflection past the critical angle, partial reflection before it.
        let cos_critical = ((1.0 - eta) * (1.0 + eta)).sqrt();
        for i in 0..200 {
            let c = cos_critical * i as f64 / 200.0;
            assert_eq!(fresnel_reflectance(c, eta), 1.0, "eta {eta} cos {c}");
        }
        for i in 1..=200 {
            let c = cos_critical + (1.0 - cos_critical) * i as f64 / 200.0;
            let f = fresnel_reflectance(c, eta);
            assert!(f < 1.0 && f > 0.0, "eta {eta} cos {c}: {f}");
        }
        // Continuous at the critical angle: F_r -> 1 from above.
        assert!(fresnel_reflectance(cos_critical * (1.0 + 1e-10), eta) > 0.99);
    }
    for eta in [1.0 / 3.0, 0.7, 1.3, 1.5, 3.0_f64] {
        // Normal incidence: ((eta - 1)/(eta + 1))^2.
        let normal = ((eta - 1.0) / (eta + 1.0)).powi(2);
        assert!(rel(fresnel_reflectance(1.0, eta), normal) < 1e-14);
        // Reciprocity: the same interface crossed the other way reflects the same.
        for i in 1..100 {
            let cos_i = i as f64 / 100.0;
            let sin_t_sq = (1.0 - cos_i * cos_i) / (eta * eta);
            if sin_t_sq < 1.0 {
                let cos_t = (1.0 - sin_t_sq).sqrt();
                let (a, b) = (fresnel_reflectance(cos_i, eta), fresnel_reflectance(cos_t, 1.0 / eta));
                assert!((a - b).abs() < 1e-12, "eta {eta} cos {cos_i}: {a} vs {b}");
            }
        }
        // Grazing incidence from the denser side of nothing: F_r(0) = 1 for eta != 1.
        assert_eq!(fresnel_reflectance(0.0, eta), 1.0);
    }
}

#[test]
fn fresnel_moment_matches_brute_force_and_reciprocity() {
    for eta in [1.0 / 3.0, 0.5, 1.0 / 1.5, 1.0 / 1.3, 0.95, 1.001, 1.05, 1.3, 1.33, 1.5, 2.0, 3.0] {
        // Midpoint rule with 2e6 cells: the kink at the critical angle limits it to ~1e-9.
        let n = 2_000_000;
        let brute: f64 = (0..n)
            .map(|i| {
                let mu = (i as f64 + 0.5) / n as f64;
                fresnel_reflectance(mu, eta) * mu
            })
            .sum::<f64>()
            / n as f64;
        let fm1 = fresnel_moment1(eta);
        assert!((fm1 - brute).abs() < 1e-8, "eta {eta}: FM1 {fm1} vs brute force {brute}");
        // Hemispherical transmittance inside = outside / eta^2 (radiance compression).
        let (t_out, t_in) = (fresnel::diffuse_transmittance(eta), fresnel::diffuse_transmittance(1.0 / eta));
        assert!((t_in - t_out / (eta * eta)).abs() < 1e-10, "eta {eta}: {t_in} vs {}", t_out / (eta * eta));
    }
    // The F_dr fit approximates the exact internal diffuse reflectance 2 FM1(1/eta).
    println!(" eta   F_dr fit  2 FM1(1/eta)");
    for eta in [1.1, 1.3, 1.5, 2.0, 2.5] {
        let (fit, exact) = (fresnel::F_dr(eta), 2.0 * fresnel_moment1(1.0 / eta));
        println!("{eta:4.2}  {fit:.5}   {exact:.5}");
        assert!((fit - exact).abs() < 0.01, "eta {eta}: fit {fit} vs exact {exact}");
    }
}

#[test]
fn bssrdf_normalization_conserves_energy() {
    for name in ["marble", "skin1", "ketchup", "spectralon", "wholemilk"] {
        let m = Material::preset(name).unwrap();
        let t_eta = m.diffuse_transmittance();
        for d in m.dipoles(1.0).unwrap() {
            // integral over the outgoing hemisphere of S_d cos(theta_o), per R_d(r) F_t(theta_i):
            // must be 1, so that the outgoing radiance integrates to the exitance R_d.
            let n = 200_000;
            let lobe: f64 = (0..n)
                .map(|i| {
                    let mu = (i as f64 + 0.5) / n as f64; // cos theta_o; dw = 2 pi dmu
                    d.s_d(d.z_r, 1.0, mu, t_eta) * mu * 2.0 * PI / n as f64
                })
                .sum();
            let per_exitance = lobe / (d.r_d(d.z_r) * fresnel_transmittance(1.0, d.eta));
            assert!(rel(per_exitance, 1.0) < 1e-6, "{name}: lobe integrates to {per_exitance}");
            // A uniformly lit plane: reflected flux / incident flux = F_t(theta_i) R_d,total <= 1
            // for every angle of incidence, and under diffuse light T(eta) R_d,total <= 1.
            for cos_i in [1.0, 0.5, 0.1, 0.0] {
                let plane = fresnel_transmittance(cos_i, d.eta) * d.r_d_total();
                assert!(plane <= 1.0, "{name}: plane reflects {plane}");
            }
            assert!(t_eta * d.r_d_total() <= 1.0);
        }
    }
}

// ---------------------------------------------------------------- the near-field kernel

/// Sum of a kernel over a square lattice of spacing `h` (a plane of samples of area h^2 under
/// uniform irradiance, seen from the sample at the origin), out to radius `rc`. Returns
/// (point kernel sum, footprint kernel sum). Octant symmetry.
fn lattice_sums(d: &Dipole, h: f64, rc: f64) -> (f64, f64) {
    let n = (rc / h).ceil() as i64;
    let area = h * h;
    (0..=n)
        .into_par_iter()
        .map(|i| {
            let (mut p, mut k) = (0.0, 0.0);
            for j in 0..=i {
                let r = h * ((i * i + j * j) as f64).sqrt();
                if r > rc {
                    break;
                }
                let mult = if i == 0 {
                    1.0
                } else if j == 0 || j == i {
                    4.0
                } else {
                    8.0
                };
                p += mult * point_kernel(d, r, area);
                k += mult * footprint_kernel(d, r, area);
            }
            (p, k)
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
}

#[test]
fn kernel_plane_reflects_total_for_every_spacing() {
    // Channels chosen to span the regimes: z_r / diffusion length from 0.009 (cream) to 1.7
    // (ketchup green), albedo from 0.003 (sprite) to 0.9999.
    let cases = [
        ("marble", 0),
        ("cream", 0),
        ("ketchup", 1),
        ("skin1", 2),
        ("apple", 2),
        ("chicken1", 0),
        ("espresso", 0),
        ("regular milk", 2),
        ("sprite", 0),
    ];
    let ratios: Vec<f64> = (-6..=6).map(|k| 10f64.powf(k as f64 / 2.0)).collect();
    println!("Uniformly lit plane of samples on a grid of spacing h: sum of kernels / R_d,total - 1");
    println!("{:>24} {:>10} {:>10} {:>12} {:>12}", "channel", "L/h", "z_r/h", "point", "footprint");
    let mut worst_point = vec![0.0f64; ratios.len()];
    let mut worst_kernel = vec![0.0f64; ratios.len()];
    for (name, c) in cases {
        let d = Material::preset(name).unwrap().dipoles(1.0).unwrap()[c];
        let total = d.r_d_total();
        // Out to where less than 1e-5 of R_d,total remains.
        let rc = d.truncation_radius(1e-5);
        for (k, &ratio) in ratios.iter().enumerate() {
            let h = d.diffusion_length() / ratio;
            let (p, f) = lattice_sums(&d, h, rc.max(2.0 * h));
            let (ep, ef) = (p / total - 1.0, f / total - 1.0);
            println!("{:>24} {ratio:>10.3e} {:>10.3e} {ep:>12.3e} {ef:>12.3e}", format!("{name} [{c}]"), d.z_r / h);
            worst_point[k] = worst_point[k].max(ep.abs());
            worst_kernel[k] = worst_kernel[k].max(ef.abs());
        }
    }
    eprintln!("\nWorst |sum / R_d,total - 1| over {} channels:", cases.len());
    eprintln!("{:>10} {:>14} {:>14}", "L/h", "point kernel", "footprint");
    for (k, ratio) in ratios.iter().enumerate() {
        eprintln!("{ratio:>10.3e} {:>14.3e} {:>14.3e}", worst_point[k], worst_kernel[k]);
    }
    for (k, ratio) in ratios.iter().enumerate() {
        assert!(worst_kernel[k] < 0.01, "footprint kernel off by {} at L/h = {ratio}", worst_kernel[k]);
    }
    // The test has teeth: plain point evaluation fails it badly when the spacing is coarse.
    assert!(worst_point[0] > 1.0 && worst_point[ratios.len() / 2] > 0.01);
}

#[test]
fn kernel_plane_without_absorption() {
    // sigma_a = 0: no diffusion length, R_d falls as z/r^3, R_d,total = 1. Sum the lattice out to
    // 400 spacings and add the exact remainder beyond (there the kernel is the point kernel and
    // smooth on the scale of the grid).
    let d = Material::preset("spectralon").unwrap().dipoles(1.0).unwrap()[1];
    eprintln!("\nsigma_a = 0 (spectralon green), R_d,total = 1:\n{:>10} {:>12} {:>12}", "z_r/h", "point", "footprint");
    for k in -6..=4 {
        let ratio = 10f64.powf(k as f64 / 2.0);
        let h = d.z_r / ratio;
        let rc = 400.0 * h;
        let (p, f) = lattice_sums(&d, h, rc);
        let rest = d.r_d_outside(rc + 0.5 * h);
        let (ep, ef) = (p + rest - 1.0, f + rest - 1.0);
        eprintln!("{ratio:>10.3e} {ep:>12.3e} {ef:>12.3e}");
        assert!(ef.abs() < 0.01, "z_r/h = {ratio}: footprint kernel off by {ef}");
    }
}

#[test]
fn kernel_integrates_to_total_and_has_no_seams() {
    for (name, c) in [("marble", 0), ("ketchup", 2), ("spectralon", 0), ("coke", 0), ("cream", 2)] {
        let d = Material::preset(name).unwrap().dipoles(1.0).unwrap()[c];
        for area_per_z_sq in [1e-4, 1e-2, 1.0, 1e2, 1e4] {
            let area = area_per_z_sq * d.z_r * d.z_r;
            let rho = (area / PI).sqrt();
            let b = kernel::B_PER_SQRT_AREA * area.sqrt();
            // Beyond 16 b the kernel is the point kernel to 3e-5 relative (checked below), so the
            // tail is taken in closed form from R_d.
            let end = 16.0 * b;
            // Continuous integral: dA R_d,total.
            let inner = radial_integral(|r| footprint_kernel(&d, r, area), 1e-9 * rho, end, 400_000);
            let integral = inner + area * d.r_d_outside(end);
            let e = rel(integral, area * d.r_d_total());
            assert!(e < 2e-4, "{name} dA = {area_per_z_sq} z_r^2: integral off by {e}");
            // No seam: across both ends of the footprint's edge, the jump over
            // [x (1 - eps), x (1 + eps)] shrinks with eps (a seam would not): by 100x at least
            // when eps shrinks 100x for a continuous kernel, 1e4x where the slope is also 0.
            let cbump = (1.0 - kernel::BUMP_DELTA.powi(2) / 5.0).sqrt();
            for x in [rho * (cbump - kernel::BUMP_DELTA), rho * (cbump + kernel::BUMP_DELTA)] {
                let jump = |eps: f64| {
                    (footprint_kernel(&d, x * (1.0 + eps), area) - footprint_kernel(&d, x * (1.0 - eps), area)).abs()
                };
                let (coarse, fine) = (jump(1e-6), jump(1e-8));
                assert!(
                    fine <= 0.02 * coarse || fine <= 1e-14 * footprint_kernel(&d, x, area),
                    "{name}: seam at r = {x}: jump {fine:e} over 2e-8 r vs {coarse:e} over 2e-6 r"
                );
            }
            // Far from the footprint it is R_d(r) dA to a relative (beta^2 / 2) R_d''/R_d, at most
            // (15/8)(b/r)^4 (1 + sigma_tr r / 3)^2 (the module doc), and never above it (R_near >= 0).
            for f in [6.0, 16.0, 100.0] {
                let (k, p) = (footprint_kernel(&d, f * b, area), point_kernel(&d, f * b, area));
                assert!(k <= p, "{name}: K {k} above the point kernel {p} at {f} b");
                let bound = 1.1 * 15.0 / 8.0 / f.powi(4) * (1.0 + d.sigma_tr * f * b / 3.0).powi(2);
                let e = rel(k, p);
                assert!(e <= bound || p < 1e-30, "{name} dA = {area_per_z_sq} z_r^2: K off R_d dA by {e} at {f} b");
            }
        }
        // Limits at the centre: a footprint much wider than the diffusion length and z_r keeps
        // the disk integral P(rho) -> R_d,total; one much narrower than z_r is the point value.
        let wide = (1e4 * d.z_v.max(d.diffusion_length().min(1e6 * d.z_v))).powi(2);
        let k_wide = footprint_kernel(&d, 0.0, wide);
        let p_rho = d.r_d_disk((wide / PI).sqrt());
        assert!(rel(k_wide, p_rho) < 1e-3, "{name}: K(0) {k_wide} vs P(rho) {p_rho}");
        let narrow = (1e-4 * d.z_r).powi(2);
        assert!(rel(footprint_kernel(&d, 0.0, narrow), point_kernel(&d, 0.0, narrow)) < 1e-6);
        // No area, no light.
        assert_eq!(footprint_kernel(&d, 0.0, 0.0), 0.0);
    }
}

#[test]
fn near_energy_is_accurate_in_both_branches() {
    // Where the direct f64 formula still has many digits (moderate cancellation), compare it with
    // taylor_remainder on both sides of the switch between its two branches:
    // G(z^2) - G(z^2 + beta) + beta G'(z^2 + beta), G(D) = z e^(-s sqrt(D)) / sqrt(D).
    let direct = |z: f64, s: f64, beta: f64| {
        let d1 = (z * z + beta).sqrt();
        let g = |dd: f64| z * (-s * dd).exp() / dd;
        let g_prime = -z * (-s * d1).exp() * (s * d1 + 1.0) / (2.0 * d1.powi(3));
        g(z) - g(d1) + beta * g_prime
    };
    for s_z in [0.0, 0.01, 0.3, 3.0, 30.0] {
        for x in [0.02, 0.05, 0.09, 0.1, 0.11, 0.2, 1.0, 10.0] {
            let z = 2.0;
            let s = s_z / z;
            // Choose beta so that (d1 - z)/z = x.
            let d1 = z * (1.0 + x);
            let beta = d1 * d1 - z * z;
            let (a, b) = (kernel::taylor_remainder(z, s, beta), direct(z, s, beta));
            assert!(rel(a, b) < 1e-7, "s z {s_z}, spread {x}: {a} vs direct {b}");
        }
        // Far into the quadrature branch the leading Taylor term (beta^2 / 2) G''(z^2) takes over;
        // the next is smaller by about (2/3) beta G'''/G'' ~ (beta / z^2)(s z / 3 + 5/3).
        for beta_rel in [1e-4, 1e-6, 1e-8] {
            let (z, s) = (2.0, s_z / 2.0);
            let beta = beta_rel * z * z;
            let q = z;
            let g2 = z * (-s * q).exp() * (s * s * q * q + 3.0 * s * q + 3.0) / (4.0 * q.powi(5));
            let taylor = 0.5 * beta * beta * g2;
            let bound = 2.0 * beta_rel * (0.5 * s_z + 2.5);
            assert!(rel(kernel::taylor_remainder(z, s, beta), taylor) < bound, "s z {s_z}, beta {beta_rel}");
        }
    }
}

/// The half-plane beyond an edge `t` from the receiver, integrated directly: `R_near = R_d - R_far`
/// in polar coordinates about the receiver, Simpson in `ln r` from where each ray leaves the
/// surface, midpoints in the angle. Independent of `near_tail`'s closed form and of the factor's
/// 8-point angular rule.
fn near_missing_direct(d: &Dipole, b: f64, t: f64) -> f64 {
    let near = |r: f64| (d.r_d(r) - kernel::r_d_far(d, r, b)).max(0.0);
    let steps = 200;
    let mut sum = 0.0;
    for k in 0..steps {
        let theta = (k as f64 + 0.5) / steps as f64 * (PI / 2.0);
        let from = (t / theta.cos()).max(1e-6 * b);
        // radial_integral carries 2 pi; the angle's measure is dtheta / (2 pi) of it, twice
        // (both halves of the even integrand).
        sum += radial_integral(near, from, from + 200.0 * b + 50.0 * d.z_v, 2000) * (PI / 2.0) / steps as f64 / PI;
    }
    sum
}

#[test]
fn near_energy_kept_at_an_open_edge_matches_a_direct_half_plane_integral() {
    // For a marble-like and a ketchup-like channel at spacings from well under to well over the
    // diffusion length: the factor against 1 - (direct half-plane integral) / E_near, half on
    // the edge, and nothing missing from NEAR_EDGE_REACH b on.
    let cases = [("marble", presets::find("marble").unwrap()), ("ketchup", presets::find("ketchup").unwrap())];
    println!("material  channel  b/z_r   t/b   kept    direct");
    for (name, preset) in cases {
        for (c, d) in preset.material().dipoles(1.0).unwrap().iter().enumerate() {
            for b_rel in [0.3, 3.0, 30.0] {
                let b = b_rel * d.z_r;
                let total = near_energy(d, b);
                // near_tail at 0 is E_near.
                assert!(rel(kernel::near_tail(d, b * b, 0.0), total) < 1e-12, "{name} {c}");
                for t_rel in [0.0, 0.01, 0.1, 0.3, 0.7, 1.5, 3.0] {
                    let t = t_rel * b;
                    let kept = kernel::near_kept_at_edge(d, b, t);
                    let direct = 1.0 - near_missing_direct(d, b, t) / total;
                    println!("{name:8}  {c}  {b_rel:6.1}  {t_rel:5.2}  {kept:.5}  {direct:.5}");
                    assert!(
                        (kept - direct).abs() < 1e-3,
                        "{name} [{c}] b {b_rel} z_r, t {t_rel} b: {kept} vs {direct}"
                    );
                    if t_rel == 0.0 {
                        assert!((kept - 0.5).abs() < 1e-9, "on the edge half stays: {kept}");
                    }
                }
                let reach = kernel::NEAR_EDGE_REACH * (d.z_v * d.z_v + b * b).sqrt();
                let beyond = near_missing_direct(d, b, reach) / total;
                assert!(beyond < 1e-4, "{name} [{c}] b {b_rel} z_r: {beyond} of E_near lies beyond the reach");
                assert_eq!(kernel::near_kept_at_edge(d, b, reach), 1.0);
            }
        }
    }
}

/// `kernel::near_second_moment` (from the tail, by parts) against `r^2 R_near` integrated
/// directly with `R_near = R_d - R_far` pointwise; and the blend radius it sets,
/// `k^2 dA / 5 = m2`, clamped, for every channel of every preset at spacings from well under to
/// well over the diffusion length.
#[test]
fn near_second_moment_matches_a_direct_integral_and_sets_the_blend_radius() {
    for (name, d) in preset_dipoles() {
        for b_rel in [0.3, 3.0, 30.0] {
            let b = b_rel * d.z_r;
            let near = |r: f64| (d.r_d(r) - kernel::r_d_far(&d, r, b)).max(0.0);
            let hi = 1e3 * (b + d.z_v);
            let energy = radial_integral(near, 1e-7 * b, hi, 20_000);
            let moment = radial_integral(|r| r * r * near(r), 1e-7 * b, hi, 20_000);
            let m2 = kernel::near_second_moment(&d, b * b);
            if energy.is_nan() || energy <= 1e-9 * d.r_d_total() {
                // Nothing near to blend (no scattering, or b far under z): the direct difference
                // is rounding, and the moment is finite.
                assert!(m2.is_finite() && m2 >= 0.0, "{name} b {b_rel} z_r: {m2}");
                continue;
            }
            assert!(rel(m2, moment / energy) < 1e-3, "{name} b {b_rel} z_r: {m2} vs {}", moment / energy);
            let area = (b / kernel::B_PER_SQRT_AREA).powi(2);
            let k = kernel::near_blend_radii(&[d; 3], area)[0];
            let want = (5.0 * m2 / area).sqrt().clamp(kernel::NEAR_BLEND_RADIUS, kernel::NEAR_BLEND_RADIUS_MAX);
            assert!(rel(k, want) < 1e-12, "{name} b {b_rel} z_r: k {k} vs {want}");
        }
    }
    let d = presets::find("marble").unwrap().material().dipoles(1.0).unwrap();
    assert_eq!(kernel::near_blend_radii(&d, 0.0), [kernel::NEAR_BLEND_RADIUS; 3]);
    assert_eq!(kernel::near_blend_radii(&d, f64::NAN), [kernel::NEAR_BLEND_RADIUS; 3]);
}

#[test]
fn kernel_stays_finite_in_hard_cases() {
    let mut count = 0;
    for sigma_s_prime in [1e-6, 1e-3, 1.0, 1e2, 1e4] {
        for sigma_a in [0.0, 1e-6, 1e-2, 1.0, 1e4] {
            for eta in [fresnel::ETA_MIN, 0.8, 1.0, 1.3, fresnel::ETA_MAX] {
                for scale in [1e-3, 1.0, 1e3] {
                    let m = Material::new("hard", [sigma_a; 3], [sigma_s_prime; 3], eta).unwrap();
                    let d = m.dipoles(scale).unwrap()[0];
                    for area_f in [1e-8, 1e-2, 1.0, 1e2, 1e8] {
                        let area = area_f * d.z_r * d.z_r;
                        for r_f in [0.0, 1e-6, 0.5, 1.0, 10.0, 1e3, 1e6] {
                            let r = r_f * d.z_r;
                            let v = [
                                d.r_d(r),
                                d.r_d_disk(r),
                                footprint_kernel(&d, r, area),
                                d.s_d(r, 0.3, 0.0, m.diffuse_transmittance()),
                            ];
                            assert!(
                                v.iter().all(|x| x.is_finite() && *x >= 0.0),
                                "{sigma_a} {sigma_s_prime} {eta} {scale}: {v:?}"
                            );
                            count += 1;
                        }
                    }
                }
            }
        }
    }
    println!("{count} hard-case evaluations, all finite and >= 0");
}

// ---------------------------------------------------------------- records, presets, errors

#[test]
fn std430_records_have_pinned_layouts() {
    use std::mem::{offset_of, size_of};
    assert_eq!(size_of::<DipoleChannelGpu>(), 16);
    assert_eq!(offset_of!(DipoleChannelGpu, z_v), 12);
    assert_eq!(size_of::<DipoleEvalInput>(), 48);
    assert_eq!(offset_of!(DipoleEvalInput, sigma_a), 0);
    assert_eq!(offset_of!(DipoleEvalInput, mm_per_unit), 12);
    assert_eq!(offset_of!(DipoleEvalInput, r), 16);
    assert_eq!(offset_of!(DipoleEvalInput, area), 20);
    assert_eq!(offset_of!(DipoleEvalInput, cos_theta_o), 28);
    assert_eq!(offset_of!(DipoleEvalInput, t_eta), 32);
    assert_eq!(size_of::<DipoleEvalOutput>(), 72);
    assert_eq!(offset_of!(DipoleEvalOutput, near_kept_edge), 68);
    assert_eq!(offset_of!(DipoleEvalOutput, F_dr), 12);
    assert_eq!(offset_of!(DipoleEvalOutput, r_d), 28);
    assert_eq!(offset_of!(DipoleEvalOutput, kernel), 40);
    assert_eq!(offset_of!(DipoleEvalOutput, near_energy), 44);
    assert_eq!(offset_of!(DipoleEvalOutput, r_d_far_cluster), 52);
    assert_eq!(offset_of!(DipoleEvalOutput, s_d), 64);
    // And the GLSL declares the same fields in the same order.
    let glsl = include_str!("../glsl/dipole_eval.comp");
    let fields = |block: &str| -> Vec<String> {
        let start = glsl.find(&format!("struct {block} {{")).unwrap();
        let body = &glsl[start..start + glsl[start..].find("};").unwrap()];
        body.lines()
            .skip(1)
            .filter_map(|l| l.trim().strip_prefix("float "))
            .map(|l| l.split(';').next().unwrap().trim().to_string())
            .collect()
    };
    assert_eq!(fields("EvalInput").len() * 4, size_of::<DipoleEvalInput>());
    assert_eq!(fields("EvalOutput").len() * 4, size_of::<DipoleEvalOutput>());
    assert_eq!(fields("EvalOutput")[3], "F_dr");
    assert_eq!(fields("EvalOutput")[10], "kernel");
    assert_eq!(fields("EvalInput")[8], "t_eta");
}

#[test]
fn presets_are_complete_valid_and_found_by_any_case() {
    assert_eq!(JENSEN_2001.len(), 12);
    assert_eq!(NARASIMHAN_2006.len(), 35);
    let mut keys = std::collections::HashSet::new();
    for m in presets::all() {
        assert!(keys.insert(presets::name_key(m.name)), "{} collides", m.name);
        let valid = Material::new(m.name, m.sigma_a, m.sigma_s_prime, m.eta).unwrap();
        assert_eq!(valid, m.material());
        for d in valid.dipoles(1.0).unwrap() {
            let t = d.r_d_total();
            assert!((0.0..=1.0).contains(&t));
        }
    }
    for name in ["marble", "MARBLE", "Marble", "lowfat milk", "Lowfat-Milk", "LOWFAT_MILK", "head & shoulders shampoo"]
    {
        assert!(Material::preset(name).is_ok(), "{name}");
    }
    assert_eq!(Material::preset("marble").unwrap().eta, 1.5);
    assert!(JENSEN_2001.iter().filter(|m| m.name != "Marble").all(|m| m.eta == 1.3));
    assert_eq!(Material::preset("granite"), Err(OpticsError::UnknownPreset("granite".into())));
    assert!(Material::preset("").is_err());
}

#[test]
fn bad_input_is_refused_with_the_value_named() {
    let msg = |e: OpticsError| e.to_string();
    let e = Material::new("x", [-0.1, 0.0, 0.0], [1.0; 3], 1.3).unwrap_err();
    assert!(msg(e.clone()).contains("-0.1") && msg(e).contains("sigma_a"));
    let e = Material::new("x", [0.1; 3], [1.0, f64::NAN, 1.0], 1.3).unwrap_err();
    assert!(msg(e.clone()).contains("NaN") && msg(e.clone()).contains("sigma_s'") && msg(e).contains("channel G"));
    assert!(msg(Material::new("x", [f64::INFINITY; 3], [1.0; 3], 1.3).unwrap_err()).contains("inf"));
    for eta in [0.0, -1.3, f64::NAN, 0.2, 5.0] {
        let e = Material::new("x", [0.1; 3], [1.0; 3], eta).unwrap_err();
        assert!(matches!(e, OpticsError::BadEta(v) if v.to_bits() == eta.to_bits()));
        assert!(msg(e).contains(&format!("eta = {eta}")));
    }
    assert!(matches!(Material::new("x", [0.0; 3], [0.0; 3], 1.3), Err(OpticsError::NoExtinction { channel: 0 })));
    let m = Material::preset("marble").unwrap();
    for scale in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(msg(m.dipoles(scale).unwrap_err()).contains(&format!("scale = {scale}")));
    }
    assert!(matches!(m.dipoles(1e-20), Err(OpticsError::OutOfRange { .. })));
    assert!(matches!(Material::from_sigma_s("x", [0.1; 3], [1.0; 3], 1.0, 1.3), Err(OpticsError::BadG(_))));
    let with_g = Material::from_sigma_s("x", [0.1; 3], [2.0; 3], 0.75, 1.3).unwrap();
    assert_eq!(with_g.sigma_s_prime, [0.5; 3]);
    assert!(m.with_eta(0.0).is_err());
}

// ---------------------------------------------------------------- the CLI

fn cli(args: &[&str]) -> std::process::Output {
    common::subcommand("material", args)
}

#[test]
fn cli_prints_derived_quantities_as_json() {
    let out = cli(&["MARBLE", "--json", "--scale", "10"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["name"], "Marble");
    assert_eq!(v["eta"], 1.5);
    let ds = Material::preset("marble").unwrap().dipoles(10.0).unwrap();
    let channels = v["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 3);
    for (c, d) in channels.iter().zip(&ds) {
        for (key, want) in [
            ("r_d_total", d.r_d_total()),
            ("mean_free_path", d.mean_free_path()),
            ("diffusion_length", d.diffusion_length()),
            ("sigma_tr", d.sigma_tr),
            ("z_v", d.z_v),
            ("A", d.A),
        ] {
            // serde_json's default parser may be 1 ulp off; the printing is shortest-exact.
            assert!(rel(c[key].as_f64().unwrap(), want) < 1e-15, "{key}");
        }
    }
    // Without absorption the diffusion length is infinite: JSON null, the table says inf.
    let out = cli(&["--sigma-a", "0", "--sigma-s-prime", "1,2,3", "--eta", "1.0", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["channels"][0]["diffusion_length"].is_null());
    assert_eq!(v["channels"][2]["r_d_total"], 1.0);
    let table = String::from_utf8(cli(&["skin1", "--eta", "1.4"]).stdout).unwrap();
    assert!(table.contains("Skin1") && table.contains("eta 1.4") && table.contains("diffusion length"));
}

#[test]
fn cli_lists_every_preset() {
    let out = cli(&["--list"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for m in presets::all() {
        assert!(text.lines().any(|l| l.starts_with(m.name)), "{} missing", m.name);
    }
    let v: serde_json::Value = serde_json::from_slice(&cli(&["--list", "--json"]).stdout).unwrap();
    assert_eq!(v.as_array().unwrap().len(), JENSEN_2001.len() + NARASIMHAN_2006.len());
}

#[test]
fn cli_refuses_bad_input_with_a_message_and_nonzero_exit() {
    for (args, needle) in [
        (&["granite"][..], "granite"),
        (&["marble", "--eta", "0"], "eta = 0"),
        (&["marble", "--eta", "-1.5"], "eta = -1.5"),
        (&["marble", "--scale", "-2"], "scale = -2"),
        (&["--sigma-a", "0.1,-0.5,0.1", "--sigma-s-prime", "1", "--eta", "1.3"], "sigma_a = -0.5"),
        (&["--sigma-a", "0.1", "--sigma-s-prime", "NaN", "--eta", "1.3"], "sigma_s' = NaN"),
        (&["--sigma-a", "0.1", "--sigma-s-prime", "1,x,1", "--eta", "1.3"], "\"x\""),
        (&["--sigma-a", "0.1", "--sigma-s-prime", "1"], "--eta"),
        (&[], "--list"),
    ] {
        let out = cli(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

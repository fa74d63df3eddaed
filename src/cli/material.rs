//! `translucent material`: a material's derived dipole quantities per channel, or the presets.
//!
//! - `translucent material --list [--json]`
//! - `translucent material NAME [--eta X] [--scale MM_PER_UNIT] [--json]`
//! - `translucent material --sigma-a R,G,B --sigma-s-prime R,G,B --eta X [--scale ..] [--json]`
//! - `... --rte [--rte-stderr REL] [--rte-photons N]`: beside each channel's `R_d,total`, the
//!   half-space total diffuse reflectance by Monte Carlo radiative transfer (`reference::rte`),
//!   split into what left after one scattering and after more, beside the single-scattering
//!   closed form (`optics::single_scatter`) and the dipole with it added.

use anyhow::{Context, bail};
use std::fmt::Write as _;
use std::io::Write as _;
use translucent::optics::presets::{self, MeasuredMaterial};
use translucent::optics::single_scatter;
use translucent::optics::{Dipole, Material};
use translucent::reference::rte::{self, Budget, Medium, Orders, RteProgress};

#[derive(clap::Args, Debug)]
#[command(after_help = "Coefficients are in 1/mm; derived lengths are in scene units \
    (1 scene unit = --scale mm). Preset names match case-insensitively, ignoring spaces and \
    punctuation: marble, skin1, \"lowfat milk\", lowfat-milk.")]
pub struct Args {
    /// A measured material (see --list), e.g. marble, skin1, ketchup, "regular milk"
    #[arg(conflicts_with_all = ["list", "sigma_a", "sigma_s_prime"])]
    pub name: Option<String>,
    /// List the measured materials (Jensen et al. 2001; Narasimhan et al. 2006)
    #[arg(long)]
    pub list: bool,
    /// Custom absorption coefficient sigma_a in 1/mm: R,G,B or one value for all channels
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true, requires = "sigma_s_prime")]
    pub sigma_a: Option<String>,
    /// Custom reduced scattering coefficient sigma_s' in 1/mm: R,G,B or one value
    #[arg(long = "sigma-s-prime", value_name = "R,G,B", allow_hyphen_values = true, requires = "sigma_a")]
    pub sigma_s_prime: Option<String>,
    /// Relative index of refraction (a preset's own by default; required with custom coefficients)
    #[arg(long, allow_hyphen_values = true)]
    pub eta: Option<f64>,
    /// Scene scale: millimetres per scene unit
    #[arg(long, value_name = "MM_PER_UNIT", default_value_t = 1.0, allow_hyphen_values = true)]
    pub scale: f64,
    /// Print JSON instead of a table
    #[arg(long)]
    pub json: bool,
    /// Also estimate each channel's half-space total diffuse reflectance by Monte Carlo
    /// radiative transfer (normal incidence, reduced coefficients walked with isotropic
    /// scattering) and show the dipole's R_d,total against it
    #[arg(long, conflicts_with = "list")]
    pub rte: bool,
    /// With --rte: stop each channel at this relative standard error
    #[arg(long, value_name = "REL", default_value_t = 0.002, allow_hyphen_values = true)]
    pub rte_stderr: f64,
    /// With --rte: walk at most this many photons per channel
    #[arg(long, value_name = "N", default_value_t = 20_000_000)]
    pub rte_photons: u64,
}

/// The seed of `--rte`'s photons: fixed, so the command prints the same figures on every run.
const RTE_SEED: u64 = 1;

pub fn run(args: &Args) -> anyhow::Result<()> {
    let text = render(args)?;
    // A closed pipe (`| head`) is not an error worth a panic or a message.
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => Ok(other?),
    }
}

/// Everything `run` prints, as one string.
fn render(args: &Args) -> anyhow::Result<String> {
    if args.list {
        return list(args.json);
    }
    let (material, source) = match (&args.name, &args.sigma_a, &args.sigma_s_prime) {
        (Some(name), _, _) => {
            let preset = presets::find(name)?;
            let material = match args.eta {
                Some(eta) => preset.material().with_eta(eta)?,
                None => preset.material(),
            };
            (material, Some(preset.source.citation()))
        }
        (None, Some(sigma_a), Some(sigma_s_prime)) => {
            let Some(eta) = args.eta else {
                bail!("--eta is required with custom coefficients (e.g. --eta 1.3)");
            };
            let sigma_a = parse_rgb("--sigma-a", sigma_a)?;
            let sigma_s_prime = parse_rgb("--sigma-s-prime", sigma_s_prime)?;
            (Material::new("custom", sigma_a, sigma_s_prime, eta)?, None)
        }
        _ => bail!(
            "name a material (`translucent material marble`), give --sigma-a R,G,B \
             --sigma-s-prime R,G,B --eta X, or use --list"
        ),
    };
    let dipoles = material.dipoles(args.scale)?;
    let rte = if args.rte { Some(half_space_rte(&dipoles, args)?) } else { None };
    if args.json {
        Ok(serde_json::to_string_pretty(&report(&material, source, args.scale, &dipoles, rte.as_ref()))? + "\n")
    } else {
        let mut out = table(&material, source, args.scale, &dipoles);
        if let Some(rte) = &rte {
            out += &rte_table(&dipoles, rte, args);
        }
        Ok(out)
    }
}

/// Per channel, the half-space total diffuse reflectance by Monte Carlo (`--rte`), with a
/// progress bar on stderr.
fn half_space_rte(dipoles: &[Dipole; 3], args: &Args) -> anyhow::Result<[Orders; 3]> {
    if !(args.rte_stderr.is_finite() && args.rte_stderr > 0.0) {
        bail!("--rte-stderr: {} is not a relative standard error > 0 (e.g. 0.002)", args.rte_stderr);
    }
    if args.rte_photons == 0 {
        bail!("--rte-photons: 0 photons estimate nothing (e.g. --rte-photons 1000000)");
    }
    let budget = Budget { max_photons: args.rte_photons, relative_stderr: Some(args.rte_stderr), max_seconds: None };
    let bar = super::progress::bar(args.rte_photons);
    let mut out = Vec::new();
    for (d, channel) in dipoles.iter().zip(["R", "G", "B"]) {
        let progress = |p: RteProgress| {
            bar.set_position(p.photons);
            bar.set_message(format!("{channel}: relative standard error {:.2e}", p.relative_stderr));
        };
        bar.reset();
        out.push(rte::half_space_by_order(&Medium::reduced(d), 1.0, &budget, RTE_SEED, &progress)?);
    }
    bar.finish_and_clear();
    Ok([out[0], out[1], out[2]])
}

/// The `--rte` rows under the table.
fn rte_table(dipoles: &[Dipole; 3], orders: &[Orders; 3], args: &Args) -> String {
    let rte = orders.map(|o| o.total);
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Half-space, normal incidence, per unit flux entering; Monte Carlo radiative transfer \
         (isotropic, sigma_s = sigma_s'; to {} relative standard error or {} photons, seed {RTE_SEED}):",
        args.rte_stderr, args.rte_photons
    );
    let _ = writeln!(out, "{:<26}{:>13}{:>13}{:>13}", "", "R", "G", "B");
    let mut row = |label: &str, cells: [String; 3]| {
        let _ = writeln!(out, "{label:<26}{}", cells.map(|c| format!("{c:>13}")).join(""));
    };
    row("R_d,total (RTE)", rte.map(|e| fmt(e.mean)));
    row("  standard error", rte.map(|e| fmt(e.stderr)));
    row("  photons", rte.map(|e| e.photons.to_string()));
    row("R_d,total (dipole)", dipoles.map(|d| fmt(d.r_d_total())));
    let difference = |d: f64, m: f64| {
        if m > 0.0 {
            format!("{:+.2}%", 100.0 * (d / m - 1.0))
        } else if d == 0.0 {
            "both 0".into()
        } else {
            "n/a".into()
        }
    };
    row("dipole vs RTE", [0, 1, 2].map(|c| difference(dipoles[c].r_d_total(), rte[c].mean)));
    let walked = |e: Option<rte::Estimate>| e.map_or("-".to_string(), |e| fmt(e.mean));
    row("  once scattered (RTE)", orders.map(|o| walked(o.single)));
    row("  more often (RTE)", orders.map(|o| walked(o.multiple)));
    let single = dipoles.each_ref().map(single_scattering);
    row("single scattering R1", single.map(fmt));
    row(
        "R1 vs once scattered",
        [0, 1, 2].map(|c| orders[c].single.map_or("-".into(), |e| difference(single[c], e.mean))),
    );
    row(
        "dipole vs more often",
        [0, 1, 2].map(|c| orders[c].multiple.map_or("-".into(), |e| difference(dipoles[c].r_d_total(), e.mean))),
    );
    row("dipole + R1 vs RTE", [0, 1, 2].map(|c| difference(dipoles[c].r_d_total() + single[c], rte[c].mean)));
    out
}

/// "1,2,3" -> [1, 2, 3]; "0.5" -> [0.5; 3]. Range checks are the material's job.
fn parse_rgb(flag: &str, text: &str) -> anyhow::Result<[f64; 3]> {
    let values = text
        .split(',')
        .map(|part| {
            let part = part.trim();
            part.parse::<f64>().with_context(|| format!("{flag}: {part:?} is not a number"))
        })
        .collect::<anyhow::Result<Vec<f64>>>()?;
    match values[..] {
        [v] => Ok([v; 3]),
        [r, g, b] => Ok([r, g, b]),
        _ => bail!("{flag}: expected R,G,B or one value, got {text:?} ({} values)", values.len()),
    }
}

#[allow(non_snake_case)]
#[derive(serde::Serialize)]
struct ChannelReport {
    channel: &'static str,
    sigma_a: f64,
    sigma_s_prime: f64,
    sigma_t_prime: f64,
    alpha_prime: f64,
    D: f64,
    sigma_tr: f64,
    F_dr: f64,
    A: f64,
    z_r: f64,
    z_v: f64,
    r_d_total: f64,
    mean_free_path: f64,
    /// `null` without absorption (infinite).
    diffusion_length: Option<f64>,
    /// `--rte`: the half-space total diffuse reflectance by Monte Carlo radiative transfer.
    #[serde(skip_serializing_if = "Option::is_none")]
    rd_total_rte: Option<f64>,
    /// `--rte`: its standard error.
    #[serde(skip_serializing_if = "Option::is_none")]
    rd_total_rte_stderr: Option<f64>,
    /// `--rte`: the photons it took.
    #[serde(skip_serializing_if = "Option::is_none")]
    rd_total_rte_photons: Option<u64>,
    /// `--rte`: the dipole's `R_d,total` (as `r_d_total`), beside it.
    #[serde(skip_serializing_if = "Option::is_none")]
    rd_total_dipole: Option<f64>,
    /// `--rte`: of `rd_total_rte`, what left after exactly one scattering (absent where the
    /// walk was not needed: no absorption or no scattering).
    #[serde(skip_serializing_if = "Option::is_none")]
    rd_single_rte: Option<f64>,
    /// `--rte`: its standard error.
    #[serde(skip_serializing_if = "Option::is_none")]
    rd_single_rte_stderr: Option<f64>,
    /// `--rte`: of `rd_total_rte`, what left after two or more scatterings.
    #[serde(skip_serializing_if = "Option::is_none")]
    rd_multiple_rte: Option<f64>,
    /// `--rte`: the single-scattering reflectance `R1` at normal incidence
    /// (`optics::single_scatter::reflectance`, isotropic, reduced albedo).
    #[serde(skip_serializing_if = "Option::is_none")]
    rd_single: Option<f64>,
}

/// `R1` at normal incidence of the medium the walk sees (reduced albedo, isotropic).
fn single_scattering(d: &Dipole) -> f64 {
    single_scatter::reflectance(d.alpha_prime, 0.0, d.eta, 1.0)
}

#[derive(serde::Serialize)]
struct Report<'a> {
    name: &'a str,
    source: Option<&'a str>,
    eta: f64,
    /// Scene scale; coefficients in `channels` are per scene unit, lengths in scene units.
    mm_per_unit: f64,
    sigma_a_per_mm: [f64; 3],
    sigma_s_prime_per_mm: [f64; 3],
    /// `1 - 2 FM1(eta)`, the BSSRDF normalization.
    diffuse_transmittance: f64,
    channels: Vec<ChannelReport>,
}

fn report<'a>(
    m: &'a Material,
    source: Option<&'a str>,
    scale: f64,
    dipoles: &[Dipole; 3],
    rte: Option<&[Orders; 3]>,
) -> Report<'a> {
    let channels = dipoles
        .iter()
        .zip(["R", "G", "B"])
        .enumerate()
        .map(|(c, (d, channel))| ChannelReport {
            channel,
            sigma_a: d.sigma_a,
            sigma_s_prime: d.sigma_s_prime,
            sigma_t_prime: d.sigma_t_prime,
            alpha_prime: d.alpha_prime,
            D: d.D,
            sigma_tr: d.sigma_tr,
            F_dr: d.F_dr,
            A: d.A,
            z_r: d.z_r,
            z_v: d.z_v,
            r_d_total: d.r_d_total(),
            mean_free_path: d.mean_free_path(),
            diffusion_length: Some(d.diffusion_length()).filter(|l| l.is_finite()),
            rd_total_rte: rte.map(|e| e[c].total.mean),
            rd_total_rte_stderr: rte.map(|e| e[c].total.stderr),
            rd_total_rte_photons: rte.map(|e| e[c].total.photons),
            rd_total_dipole: rte.map(|_| d.r_d_total()),
            rd_single_rte: rte.and_then(|e| e[c].single.map(|s| s.mean)),
            rd_single_rte_stderr: rte.and_then(|e| e[c].single.map(|s| s.stderr)),
            rd_multiple_rte: rte.and_then(|e| e[c].multiple.map(|s| s.mean)),
            rd_single: rte.map(|_| single_scattering(d)),
        })
        .collect();
    Report {
        name: &m.name,
        source,
        eta: m.eta,
        mm_per_unit: scale,
        sigma_a_per_mm: m.sigma_a,
        sigma_s_prime_per_mm: m.sigma_s_prime,
        diffuse_transmittance: m.diffuse_transmittance(),
        channels,
    }
}

fn table(m: &Material, source: Option<&str>, scale: f64, dipoles: &[Dipole; 3]) -> String {
    let mut out = String::new();
    let from = source.map(|s| format!(" ({s})")).unwrap_or_default();
    let _ = writeln!(out, "{}{from}: eta {}, 1 scene unit = {} mm", m.name, m.eta, scale);
    let _ = writeln!(out, "{:<26}{:>13}{:>13}{:>13}", "", "R", "G", "B");
    let mut row = |label: &str, f: &dyn Fn(&Dipole) -> f64| {
        let cells: String = dipoles.iter().map(|d| format!("{:>13}", fmt(f(d)))).collect();
        let _ = writeln!(out, "{label:<26}{cells}");
    };
    row("sigma_a          [1/mm]", &|d| d.sigma_a / scale);
    row("sigma_s'         [1/mm]", &|d| d.sigma_s_prime / scale);
    row("sigma_t'         [1/unit]", &|d| d.sigma_t_prime);
    row("alpha'", &|d| d.alpha_prime);
    row("sigma_tr         [1/unit]", &|d| d.sigma_tr);
    row("D                [unit]", &|d| d.D);
    row("F_dr", &|d| d.F_dr);
    row("A", &|d| d.A);
    row("z_r              [unit]", &|d| d.z_r);
    row("z_v              [unit]", &|d| d.z_v);
    row("R_d,total", &|d| d.r_d_total());
    row("mean free path   [unit]", &|d| d.mean_free_path());
    row("diffusion length [unit]", &|d| d.diffusion_length());
    let _ = writeln!(out, "BSSRDF normalization T(eta) = 1 - 2 FM1(eta) = {}", fmt(m.diffuse_transmittance()));
    out
}

/// Four significant digits, plain for ordinary magnitudes, scientific otherwise.
fn fmt(v: f64) -> String {
    if v.is_infinite() {
        "inf".into()
    } else if v == 0.0 || (1e-3..1e5).contains(&v.abs()) {
        let digits = if v == 0.0 { 0 } else { (3 - v.abs().log10().floor() as i32).max(0) as usize };
        format!("{v:.digits$}")
    } else {
        format!("{v:.3e}")
    }
}

fn list(json: bool) -> anyhow::Result<String> {
    let all: Vec<&MeasuredMaterial> = presets::all().collect();
    if json {
        return Ok(serde_json::to_string_pretty(&all)? + "\n");
    }
    let mut out = String::new();
    let triple = |v: [f64; 3]| v.map(|x| format!("{:>9}", fmt3(x))).join("");
    let _ = writeln!(
        out,
        "{:<28}{:<24}{:>5}  {:>27}  {:>27}  {:>21}",
        "name", "source", "eta", "sigma_s' R G B [1/mm]", "sigma_a R G B [1/mm]", "R_d,total R G B"
    );
    for m in all {
        let totals = m.material().dipoles(1.0)?.map(|d| d.r_d_total());
        let _ = writeln!(
            out,
            "{:<28}{:<24}{:>5}  {}  {}  {}",
            m.name,
            m.source.citation(),
            m.eta,
            triple(m.sigma_s_prime),
            triple(m.sigma_a),
            totals.map(|t| format!("{t:>7.3}")).join("")
        );
    }
    Ok(out)
}

/// Three significant digits in at most 8 characters.
fn fmt3(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if (1e-2..1e4).contains(&v.abs()) {
        let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.2e}")
    }
}

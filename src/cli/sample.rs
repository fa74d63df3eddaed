//! `translucent sample`: place sample points on a mesh, write them as PLY, print statistics.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Context;
use indicatif::ProgressBar;
use translucent::mesh::{LoadOptions, Mesh};
use translucent::sampling::{self, Method, SampleOptions, SamplePoint, SampleStats};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Mesh to sample (Wavefront OBJ)
    pub mesh: PathBuf,
    /// Placement method
    #[arg(long, value_parser = super::one_of::<Method>(&Method::ALL.map(Method::name)))]
    pub method: Method,
    /// Number of sample points
    #[arg(long, short = 'n')]
    pub count: usize,
    /// Random seed (the same seed gives the same points)
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write the points to this PLY file (x y z nx ny nz area)
    #[arg(long, short = 'o')]
    pub output: Option<PathBuf>,
    /// Print the statistics as JSON instead of text
    #[arg(long)]
    pub json: bool,
    /// Scale applied to the mesh positions on loading
    #[arg(long, default_value_t = 1.0)]
    pub scale: f32,
    /// Repulsion iterations (default 40 for turk, 80 for feature)
    #[arg(long)]
    pub iterations: Option<usize>,
}

#[derive(serde::Serialize)]
struct Report<'a> {
    mesh: &'a translucent::mesh::MeshReport,
    vertices: usize,
    triangles: usize,
    method: &'static str,
    seed: u64,
    #[serde(flatten)]
    stats: &'a SampleStats,
    load_seconds: f64,
    sample_seconds: f64,
    output: Option<&'a Path>,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let spinner = if args.json { ProgressBar::hidden() } else { super::progress::spinner() };
    spinner.enable_steady_tick(Duration::from_millis(100));

    spinner.set_message(format!("loading {}", args.mesh.display()));
    let t0 = Instant::now();
    let mesh = Mesh::load(&args.mesh, &LoadOptions::default().with_scale(args.scale))?;
    let load_seconds = t0.elapsed().as_secs_f64();

    let mut options = SampleOptions::new(args.method, args.count).with_seed(args.seed);
    if let Some(it) = args.iterations {
        options.turk.iterations = it;
        options.feature.turk.iterations = it;
    }
    spinner.set_message(format!("placing {} points ({})", args.count, options.method));
    let t1 = Instant::now();
    let placed = sampling::place(&mesh, &options)?;
    spinner.set_message("assigning area weights");
    let areas = sampling::weights::area_weights(&mesh, &placed, &options.weights);
    let points = sampling::finish(&mesh, &placed, &areas);
    let sample_seconds = t1.elapsed().as_secs_f64();

    spinner.set_message("statistics");
    let stats = SampleStats::compute(&points, mesh.total_area());
    if let Some(path) = &args.output {
        spinner.set_message(format!("writing {}", path.display()));
        let comment = format!(
            "translucent sample: {} points, method {}, seed {}, mesh {}",
            points.len(),
            options.method,
            args.seed,
            args.mesh.display()
        );
        write_ply_atomic(path, &points, &comment)?;
    }
    spinner.finish_and_clear();

    let report = mesh.report();
    if args.json {
        let out = Report {
            mesh: report,
            vertices: mesh.positions().len(),
            triangles: mesh.triangles().len(),
            method: options.method.name(),
            seed: args.seed,
            stats: &stats,
            load_seconds,
            sample_seconds,
            output: args.output.as_deref(),
        };
        out!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }

    for warning in mesh_warnings(report) {
        eprintln!("warning: {}: {warning}", report.source);
    }
    let fmt_opt = |v: Option<f64>| v.map_or("-".to_string(), num);
    out!("mesh         {} ({} vertices, {} triangles)", report.source, mesh.positions().len(), mesh.triangles().len());
    out!("method       {} (seed {})", options.method, args.seed);
    out!("count        {}", stats.count);
    out!(
        "total area   {} (weights sum to {}, relative difference {:.1e})",
        num(stats.mesh_area),
        num(stats.total_weight),
        (stats.total_weight - stats.mesh_area).abs() / stats.mesh_area
    );
    out!("nn distance  min {}  mean {}  max {}", fmt_opt(stats.nn_min), fmt_opt(stats.nn_mean), fmt_opt(stats.nn_max));
    out!("weights      cv {:.4}  min {:.3e}  max {:.3e}", stats.weight_cv, stats.weight_min, stats.weight_max);
    out!("time         load {load_seconds:.3} s, sampling {sample_seconds:.3} s");
    if let Some(path) = &args.output {
        out!("written      {}", path.display());
    }
    Ok(())
}

/// Six significant digits, in fixed notation for everyday magnitudes and scientific otherwise
/// (meshes may be in micrometres or kilometres).
fn num(v: f64) -> String {
    if v == 0.0 || (1e-3..1e6).contains(&v.abs()) {
        let decimals = (5 - v.abs().log10().floor() as i32).clamp(0, 8) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.5e}")
    }
}

fn mesh_warnings(r: &translucent::mesh::MeshReport) -> Vec<String> {
    let mut w = Vec::new();
    if r.degenerate_triangles > 0 {
        w.push(format!("dropped {} zero-area triangles", r.degenerate_triangles));
    }
    if r.boundary_edges > 0 {
        w.push(format!("{} open boundary edges (the surface is not closed)", r.boundary_edges));
    }
    if r.non_manifold_edges > 0 {
        w.push(format!("{} non-manifold edges (shared by three or more triangles)", r.non_manifold_edges));
    }
    if r.inconsistently_oriented_edges > 0 {
        w.push(format!(
            "{} edges with inconsistent winding (some normals may point inwards)",
            r.inconsistently_oriented_edges
        ));
    }
    w
}

/// Write an ASCII PLY to a temporary file next to `path`, then rename it into place, so a failure
/// leaves either the old file or none, never half of a new one.
fn write_ply_atomic(path: &Path, points: &[SamplePoint], comment: &str) -> anyhow::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path.file_name().with_context(|| format!("output path {} has no file name", path.display()))?;
    let tmp = dir.join(format!(".{}.tmp{}", name.to_string_lossy(), std::process::id()));
    let result = write_ply(&tmp, points, comment)
        .and_then(|()| std::fs::rename(&tmp, path))
        .with_context(|| format!("cannot write {} (through the temporary file {})", path.display(), tmp.display()));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn write_ply(path: &Path, points: &[SamplePoint], comment: &str) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    let comment = comment.replace(['\n', '\r'], " ");
    write!(
        w,
        "ply\nformat ascii 1.0\ncomment {comment}\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property float area\nend_header\n",
        points.len()
    )?;
    for p in points {
        let (x, n) = (p.position, p.normal);
        writeln!(w, "{} {} {} {} {} {} {}", x.x, x.y, x.z, n.x, n.y, n.z, p.area as f32)?;
    }
    w.into_inner().map_err(|e| e.into_error())?.sync_all()
}

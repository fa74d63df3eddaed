//! `translucent study [SCENE] -o DIR`: what accuracy costs in time, against the exact dipole
//! integral (`translucent::study`).

use anyhow::{Context, Result, bail};
use indicatif::ProgressStyle;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use translucent::gpu::Gpu;
use translucent::output::OutputSet;
use translucent::reference::rte::Budget;
use translucent::reference::rte_mesh::{MeshOptions, Walk};
use translucent::reference::truth;
use translucent::sampling::Method;
use translucent::scene::{GatherMode, MAX_GATHER_EPSILON, MAX_SAMPLE_COUNT, Scene, SplatVisibility};
use translucent::study::physics::Model;
use translucent::study::{self, Event, StudyConfig, report};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file (TOML); the built-in marble bunny when omitted
    pub scene: Option<PathBuf>,
    /// Folder for study.csv, study.md, study.png, truth.png and, with --physics, light.png (made if
    /// missing)
    #[arg(short, long)]
    pub output: PathBuf,
    /// A few configurations and one seed (seconds on a small scene), instead of the full sweep
    #[arg(long)]
    pub quick: bool,
    /// Seeds per configuration (the full sweep's default is 3)
    #[arg(long)]
    pub seeds: Option<u64>,
    /// Only these samplers, comma-separated (default: all four; random, turk, feature, poisson)
    #[arg(long, value_delimiter = ',', value_name = "SAMPLER,...")]
    pub samplers: Vec<String>,
    /// Only these sample counts, comma-separated (default: 100 to 6400, doubling)
    #[arg(long, value_delimiter = ',', value_name = "N,...")]
    pub counts: Vec<usize>,
    /// Only these gathers, comma-separated: vertex, sparse, pixel, hierarchical:EPSILON,
    /// texture[:ATLAS] (default: the first three, hierarchical at 0.3, 0.1 and 0.03, texture at
    /// 128, 256 and 512; the texture gather takes each count as its draws per receiver, first
    /// sampler and seed only)
    #[arg(long, value_delimiter = ',', value_name = "GATHER,...")]
    pub gathers: Vec<String>,
    /// Also draw per-vertex relative error on the model for one configuration,
    /// SAMPLER:COUNT[:GATHER] (gather vertex by default; first seed), to error.png
    #[arg(long, value_name = "SAMPLER:COUNT[:GATHER]")]
    pub error_image: Option<String>,
    /// Refine the truth to at most this level (default 5); past it the study says the truth
    /// did not converge and prints its last change between levels
    #[arg(long, value_name = "LEVEL")]
    pub truth_levels: Option<u32>,
    /// Compute the truth at no more than this many vertices per object, spread over the mesh
    /// (for large meshes; per-vertex errors then cover those vertices and the image errors and
    /// truth.png are left out)
    #[arg(long, value_name = "N")]
    pub truth_receivers: Option<usize>,
    /// The most memory one level of the truth may take, e.g. 4G or 500M (binary units; default:
    /// a quarter of the memory available when the level starts, at most 1G); a level estimated
    /// over it is refused
    #[arg(long, value_name = "SIZE")]
    pub truth_memory: Option<String>,
    /// Where the truth is cached, keyed by the scene's content (default: the user's cache
    /// folder, translucent/truth)
    #[arg(long)]
    pub truth_cache: Option<PathBuf>,
    /// Which configurations, comma-separated: `default` (the scene's own: the counts its error
    /// target chooses and its gather, a row labelled default), `sweep` (default: both)
    #[arg(long, value_delimiter = ',', value_name = "default|sweep")]
    pub configurations: Vec<String>,
    /// The error target the `default` row's counts are chosen for, e.g. 0.01 (overrides
    /// render.max_error)
    #[arg(long)]
    pub max_error: Option<f64>,
    /// How every row's splat finds whether a light reaches a sample: hybrid, rays or
    /// shadow_maps (overrides render.splat_visibility)
    #[arg(long, value_parser = super::one_of::<SplatVisibility>(&SplatVisibility::ALL.map(SplatVisibility::name)))]
    pub splat_visibility: Option<SplatVisibility>,
    /// Split each row's error against the physics: the model error (the dipole's exact
    /// integral against a Monte Carlo radiative-transfer reference walked in each mesh), the
    /// discretisation error (the renderer against the dipole integral) and the total error (the
    /// renderer against the reference). The reference is cached beside the truth.
    #[arg(long)]
    pub physics: bool,
    /// With --physics: stop the reference once its precision (worst channel) is at most this
    /// (default 0.01): for the adjoint walk the RMS over lit receivers of each one's relative
    /// standard error, for the photon walk the RMS standard error over lit vertices over their
    /// mean
    #[arg(long, allow_hyphen_values = true, value_name = "REL")]
    pub rte_stderr: Option<f64>,
    /// With --physics: walk at most this many walks per receiver (adjoint) or photons per
    /// object (photons) (default 1000000000)
    #[arg(long, value_name = "N")]
    pub rte_photons: Option<u64>,
    /// With --physics: how the reference walks: `adjoint` (backwards from each receiver to the
    /// lights' beams, each receiver to its own precision), `photons` (from the lights, tallied
    /// at every vertex) or `auto` (default: adjoint where a mesh has more than 16 vertices per
    /// receiver, which it then reaches sooner)
    #[arg(long, value_name = "auto|adjoint|photons")]
    pub rte_walk: Option<String>,
    /// With --physics and the adjoint or auto walk: receivers per object, spread over the mesh
    /// as --truth-receivers spreads them (default: --truth-receivers if given, else 1000)
    #[arg(long, value_name = "N")]
    pub rte_receivers: Option<usize>,
    /// With --physics: the models measured beside the dipole against the reference,
    /// comma-separated (default: none): between, per-channel, dipole+single, single,
    /// directional, directional-grosjean, directional-alpha, transport, transport-slanted; `all`
    /// for every one
    #[arg(long, value_delimiter = ',', value_name = "MODEL,...")]
    pub models: Vec<String>,
    /// With --physics: stop the reference after this many seconds per object (default 600; the
    /// photon count, and so the reference, then depends on the machine)
    #[arg(long, allow_hyphen_values = true, value_name = "SECONDS")]
    pub rte_seconds: Option<f64>,
    /// With --physics: sweep the renderer once per model, comma-separated (dipole, auto,
    /// single, transport), each forced on every translucent material and measured against the
    /// one reference; light.png then plots total error against frame time across them, with
    /// the Pareto front (default: the scene's own models)
    #[arg(long, value_delimiter = ',', value_name = "MODEL,...")]
    pub render_models: Vec<String>,
}

/// The seed of `--physics`'s photons: fixed, so a study is reproducible where the photon or
/// precision budget stops it.
const RTE_SEED: u64 = 1;

/// `--physics`'s budget, or `None` without it; an `--rte-*` flag without `--physics`, or a
/// value that budgets nothing, is an error naming the flag.
fn physics(args: &Args) -> Result<Option<MeshOptions>> {
    if !args.physics {
        let given = [
            ("--rte-stderr", args.rte_stderr.is_some()),
            ("--rte-photons", args.rte_photons.is_some()),
            ("--rte-seconds", args.rte_seconds.is_some()),
            ("--rte-walk", args.rte_walk.is_some()),
            ("--rte-receivers", args.rte_receivers.is_some()),
            ("--models", !args.models.is_empty()),
            ("--render-models", !args.render_models.is_empty()),
        ];
        if let Some((flag, _)) = given.into_iter().find(|g| g.1) {
            bail!("{flag}: only with --physics (it sets the radiative-transfer reference and its comparisons)");
        }
        return Ok(None);
    }
    let (stderr, photons, seconds) =
        (args.rte_stderr.unwrap_or(0.01), args.rte_photons.unwrap_or(1_000_000_000), args.rte_seconds.unwrap_or(600.0));
    if !(stderr.is_finite() && stderr > 0.0) {
        bail!("--rte-stderr {stderr}: must be a relative standard error > 0, e.g. 0.01");
    }
    if photons == 0 {
        bail!("--rte-photons 0: 0 photons estimate nothing, e.g. --rte-photons 1000000");
    }
    if !(seconds.is_finite() && seconds > 0.0) {
        bail!("--rte-seconds {seconds}: must be a time > 0 in seconds, e.g. 600");
    }
    let receivers = args.rte_receivers.or(args.truth_receivers).unwrap_or(1000);
    if receivers == 0 {
        bail!("--rte-receivers 0: the adjoint walk needs at least one receiver, e.g. 1000");
    }
    let walk = match args.rte_walk.as_deref().unwrap_or("auto") {
        "adjoint" => Walk::Adjoint { receivers: Some(receivers) },
        "auto" => Walk::Auto { receivers },
        "photons" if args.rte_receivers.is_some() => {
            bail!("--rte-receivers: only with --rte-walk adjoint (the photon walk tallies every vertex)")
        }
        "photons" => Walk::Photons,
        other => bail!("--rte-walk {other}: one of auto, adjoint, photons"),
    };
    let budget = Budget { max_photons: photons, relative_stderr: Some(stderr), max_seconds: Some(seconds) };
    Ok(Some(MeshOptions { budget, seed: RTE_SEED, walk }))
}

/// `--models`: the models named (every one for `all`), each once, in the report's order.
fn models(args: &Args) -> Result<Vec<Model>> {
    if args.models.iter().any(|m| m == "all") {
        return Ok(Model::ALL.to_vec());
    }
    let named = args.models.iter().map(|m| m.parse::<Model>().map_err(|e| anyhow::anyhow!("--models: {e}")));
    let named = named.collect::<Result<Vec<Model>>>()?;
    Ok(Model::ALL.into_iter().filter(|m| named.contains(m)).collect())
}

/// `--error-image SAMPLER:COUNT[:GATHER]`, the gather written as `--gathers` writes it
/// (`hierarchical:EPSILON` included; vertex by default).
fn parse_error_image(spec: &str) -> Result<(Method, usize, Gather)> {
    let parts: Vec<&str> = spec.splitn(3, ':').collect();
    let bad = || {
        format!(
            "--error-image {spec:?}: expected SAMPLER:COUNT[:GATHER], e.g. turk:400:vertex or turk:400:hierarchical:0.1"
        )
    };
    if parts.len() < 2 {
        bail!(bad());
    }
    let method: Method = parts[0].parse().map_err(|e: String| anyhow::anyhow!("{}: {e}", bad()))?;
    let count: usize = parts[1].parse().with_context(bad)?;
    let gather = match parts.get(2) {
        Some(g) => parse_gather(g).with_context(bad)?,
        None => (GatherMode::Vertex, None),
    };
    if gather.0 == GatherMode::Pixel {
        bail!("--error-image {spec:?}: the pixel gather has no per-vertex exitance to draw");
    }
    Ok((method, count, gather))
}

/// `items` with each repeat after the first left out (a configuration named twice is run once).
fn distinct<T: PartialEq>(items: Vec<T>) -> Vec<T> {
    let mut out: Vec<T> = Vec::with_capacity(items.len());
    for item in items {
        if !out.contains(&item) {
            out.push(item);
        }
    }
    out
}

/// A gather with the hierarchical gather's epsilon.
type Gather = (GatherMode, Option<f32>);

/// One `--gathers` entry: a gather's name, the hierarchical one with its epsilon.
fn parse_gather(spec: &str) -> Result<Gather> {
    let (name, epsilon) = match spec.split_once(':') {
        Some((n, e)) => (n, Some(e)),
        None => (spec, None),
    };
    let mode: GatherMode = name.parse().map_err(|e: String| anyhow::anyhow!("--gathers {spec:?}: {e}"))?;
    match (mode, epsilon) {
        (GatherMode::Hierarchical, None) => {
            bail!("--gathers {spec:?}: name the hierarchical gather's epsilon, e.g. hierarchical:0.1")
        }
        (GatherMode::Hierarchical, Some(e)) => {
            // `+ 0.0` makes -0 plain 0, so it prints and compares as 0.
            let eps: f32 =
                e.parse::<f32>().with_context(|| format!("--gathers {spec:?}: {e:?} is not a number"))? + 0.0;
            if !(0.0..=MAX_GATHER_EPSILON).contains(&eps) {
                bail!("--gathers {spec:?}: epsilon must be 0 to {MAX_GATHER_EPSILON}");
            }
            Ok((mode, Some(eps)))
        }
        (GatherMode::Texture, Some(r)) => {
            let resolution: u32 =
                r.parse().with_context(|| format!("--gathers {spec:?}: {r:?} is not a whole number"))?;
            let (lo, hi) = (translucent::mesh::atlas::MIN_RESOLUTION, translucent::mesh::atlas::MAX_RESOLUTION);
            if !(lo..=hi).contains(&resolution) {
                bail!("--gathers {spec:?}: the atlas resolution must be {lo} to {hi}");
            }
            Ok((mode, Some(resolution as f32)))
        }
        (_, Some(_)) => bail!(
            "--gathers {spec:?}: only the hierarchical gather (epsilon) and the texture gather (atlas resolution) take a parameter"
        ),
        (_, None) => Ok((mode, None)),
    }
}

/// `--truth-memory SIZE`: a number of bytes with an optional binary unit (K, M, G, T; `B` or
/// `iB` may follow), e.g. `4G`, `512MiB`, `1.5g`.
fn parse_size(spec: &str) -> Result<u64> {
    let bad = || format!("--truth-memory {spec:?}: expected a size such as 4G, 512M or 1.5G");
    let t = spec.trim();
    let t = t.strip_suffix("iB").or_else(|| t.strip_suffix('B')).unwrap_or(t);
    let (number, unit) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&t[..i], c.to_ascii_uppercase()),
        _ => (t, ' '),
    };
    let shift = match unit {
        ' ' => 0,
        'K' => 10,
        'M' => 20,
        'G' => 30,
        'T' => 40,
        _ => bail!(bad()),
    };
    let value: f64 = number.trim().parse().with_context(bad)?;
    let bytes = value * 2f64.powi(shift);
    if !bytes.is_finite() || bytes < 1.0 || bytes >= u64::MAX as f64 {
        bail!("--truth-memory {spec:?}: must be at least one byte and finite");
    }
    Ok(bytes as u64)
}

/// The sweep the arguments ask for.
fn config(args: &Args) -> Result<StudyConfig> {
    let mut config = if args.quick { StudyConfig::quick() } else { StudyConfig::full() };
    if !args.samplers.is_empty() {
        config.samplers = parse_each("--samplers", &args.samplers)?;
    }
    if !args.counts.is_empty() {
        if let Some(&n) = args.counts.iter().find(|&&n| n == 0 || n > MAX_SAMPLE_COUNT) {
            bail!("--counts {n}: a sample count must be 1 to {MAX_SAMPLE_COUNT}");
        }
        config.counts = distinct(args.counts.clone());
    }
    if !args.gathers.is_empty() {
        config.gathers = args.gathers.iter().map(|g| parse_gather(g)).collect::<Result<Vec<_>>>().map(distinct)?;
    }
    if let Some(level) = args.truth_levels {
        if level == 0 {
            bail!("--truth-levels 0: must be 1 to {} (level 0 has nothing to compare with)", truth::MAX_LEVEL);
        }
        if level > truth::MAX_LEVEL {
            bail!(
                "--truth-levels {level}: must be 1 to {} (each level costs about four times the one before)",
                truth::MAX_LEVEL
            );
        }
        config.truth.max_level = level;
    }
    if let Some(size) = &args.truth_memory {
        config.truth.memory = Some(parse_size(size)?);
    }
    if let Some(n) = args.truth_receivers {
        if n < 100 {
            bail!("--truth-receivers {n}: must be at least 100 (fewer make the per-vertex statistics noise)");
        }
        config.truth.receivers = Some(n);
    }
    if !args.configurations.is_empty() {
        config.own = false;
        config.sweep = false;
        for c in &args.configurations {
            match c.as_str() {
                "default" => config.own = true,
                "sweep" => config.sweep = true,
                other => bail!("--configurations {other:?}: expected default or sweep"),
            }
        }
    }
    if let Some(n) = args.seeds {
        if n == 0 {
            bail!("--seeds must be at least 1");
        }
        config.seeds = (1..=n).collect();
    }
    config.physics = physics(args)?;
    config.models = models(args)?;
    config.render_models = parse_each("--render-models", &args.render_models)?;
    Ok(config)
}

/// Each item of a comma list given to `flag`, parsed and kept once; an item that does not
/// parse is an error naming the flag and the item.
fn parse_each<T: std::str::FromStr<Err = String> + PartialEq>(flag: &str, items: &[String]) -> Result<Vec<T>> {
    let parsed = items.iter().map(|s| s.parse().map_err(|e: String| anyhow::anyhow!("{flag} {s:?}: {e}")));
    parsed.collect::<Result<Vec<T>>>().map(distinct)
}

pub fn run(gpu_args: &super::GpuArgs, args: &Args) -> Result<()> {
    let chosen = args.error_image.as_deref().map(parse_error_image).transpose()?;
    let config = config(args)?;
    check_error_image(chosen, &config)?;
    if args.output.exists() && !args.output.is_dir() {
        bail!("{} exists and is not a folder", args.output.display());
    }
    // Interrupted, it leaves no output behind and exits 130, as `render` does.
    let outputs: Vec<PathBuf> = OUTPUT_NAMES.iter().map(|n| args.output.join(n)).collect();
    super::remove_on_interrupt(&outputs.iter().collect::<Vec<_>>())?;
    let mut scene = match &args.scene {
        Some(path) => Scene::load(path)?,
        None => Scene::builtin(),
    };
    if let Some(e) = args.max_error {
        translucent::scene::check_max_error("--max-error", e)?;
        scene.file.render.max_error = e;
    }
    if let Some(v) = args.splat_visibility {
        scene.file.render.splat_visibility = v;
    }
    let gpu: Arc<Gpu> = Gpu::new(&gpu_args.options())?;
    let device = gpu.info().name.clone();
    let cache = args.truth_cache.clone().unwrap_or_else(truth::default_cache_dir);
    let study = run_with_progress(&gpu, &scene, &config, &cache).map_err(with_hint)?;

    let physics = study.physics.as_ref().map_or(String::new(), |p| study::physics::markdown(p, &study.rows));
    let preamble = preamble(&study, &scene, &config, &device) + &reference_timing(&study) + &physics;
    let summaries = report::summarise(&study.rows);
    let preamble = preamble + &study::models::markdown(&study.rows, &summaries);
    let md = report::markdown(&format!("Accuracy study: {}", scene.name), &preamble, &summaries);
    let plot = report_plot(&summaries, &format!("{}: error against frame time", scene.name))?;
    let light = study::models::against_light(&summaries);
    let light_plot = match light.is_empty() {
        true => None,
        false => Some(report_plot(
            &study::models::with_precompute(&light),
            &format!("{}: error against the light (RTE reference)", scene.name),
        )?),
    };
    write_outputs(&args.output, &study, chosen, md, (&plot, light_plot.as_deref()))?;
    for (what, summaries) in [("error", &summaries), ("against the light", &light)] {
        for target in report::TARGETS.into_iter().filter(|_| !summaries.is_empty()) {
            match report::fastest_meeting(summaries, target) {
                Some(s) => out!("{what} <= {:>4}%: {} at {:.1} ms", target * 100.0, s.label(), s.frame_ms),
                None => out!("{what} <= {:>4}%: no configuration in the sweep", target * 100.0),
            }
        }
    }
    if let Some(p) = &study.physics {
        let pct = |v: [f64; 3]| v.map(|e| format!("{:.2}%", 100.0 * e)).join(", ");
        out!(
            "model error ({} against the radiative transfer, r, g, b): {}; reference noise {}",
            p.model_name,
            pct(p.model.rel_rms),
            pct(p.noise)
        );
    }
    Ok(())
}

/// A truth level refused for memory, with the options that change it.
fn with_hint(e: anyhow::Error) -> anyhow::Error {
    match e.downcast_ref::<study::StudyError>() {
        Some(study::StudyError::Truth(truth::TruthError::Memory { level, .. })) => {
            let stop = if *level > 1 {
                format!(", or --truth-levels {} to stop before it (the truth then reads not converged)", level - 1)
            } else {
                String::new()
            };
            anyhow::anyhow!("{e:#}; --truth-memory SIZE sets the limit{stop}")
        }
        _ => e,
    }
}

/// `--error-image`'s configuration must be one the sweep renders, against a truth at every
/// vertex.
fn check_error_image(chosen: Option<(Method, usize, Gather)>, config: &StudyConfig) -> Result<()> {
    if chosen.is_some() && config.truth.receivers.is_some() {
        // The picture colours every vertex by its error; a subset truth knows only some.
        bail!("--error-image needs the truth at every vertex: leave out --truth-receivers");
    }
    if let Some((m, n, g)) = chosen {
        let swept =
            config.sweep && config.samplers.contains(&m) && config.counts.contains(&n) && config.gathers.contains(&g);
        if !swept {
            bail!(
                "--error-image: {m} with {n} samples and the {} gather is not in this sweep (samplers {:?}, counts {:?})",
                g.0.name(),
                config.samplers.iter().map(|m| m.name()).collect::<Vec<_>>(),
                config.counts
            );
        }
    }
    Ok(())
}

/// `study::run` behind a progress bar (cleared when done).
fn run_with_progress(gpu: &Arc<Gpu>, scene: &Scene, config: &StudyConfig, cache: &Path) -> Result<study::Study> {
    let bar = super::progress::bar(config.runs() as u64);
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} {runs_eta} {msg}")
            .expect("a valid template")
            .with_key("runs_eta", runs_eta),
    );
    // The clock and spinner move while one long step (a truth level, a walk) reports nothing.
    bar.enable_steady_tick(std::time::Duration::from_millis(250));
    let level_clock = TruthClock::default();
    let study = study::run(gpu, scene, config, cache, &|e| match e {
        Event::Truth(level, done, of) => {
            let left = level_clock.left(level, done, of);
            if let Some(warning) = level_clock.warning(level, left) {
                bar.println(warning);
            }
            let left = left.map_or(String::new(), |s| format!(", about {} left", human_duration(s)));
            bar.set_message(if done == 0 {
                format!("exact integral, level {level}: placing and ray casting its sources")
            } else {
                format!("exact integral, level {level}: {done}/{of} receivers{left}")
            });
        }
        Event::TruthCached => bar.set_message("exact integral from the cache".to_string()),
        Event::Rte(p) => bar.set_message(format!(
            "radiative transfer: {} walks, {:.1} s, precision {:.4}",
            p.photons, p.seconds, p.relative_stderr
        )),
        Event::RteCached => bar.set_message("radiative transfer from the cache".to_string()),
        Event::Run(i, _, label) => {
            if i == 0 {
                // The rate of configurations, not of the truth and reference before them.
                bar.reset_eta();
            }
            bar.set_position(i as u64);
            bar.set_message(label);
        }
        Event::Kernel(object, done, of) => {
            bar.set_message(format!("transport kernel of {object}: {done}/{of} patches walked"));
        }
        Event::Step(step) => bar.set_message(step_message(step)),
    })?;
    bar.finish_and_clear();
    Ok(study)
}

/// The configurations' time left, once one has run: before, the bar stands at 0 through the
/// truth and the reference, and a rate from nothing would read "0s".
fn runs_eta(state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write) {
    if state.pos() > 0 {
        let _ = write!(w, "eta {}", indicatif::HumanDuration(state.eta()));
    }
}

/// What the bar says while `step` runs.
fn step_message(step: study::Step) -> String {
    match step {
        study::Step::BetweenPoints => "single scattering between points over the scene".to_string(),
        study::Step::Model(m) => format!("model {} against the radiative transfer", m.name()),
        study::Step::TruthImage => "the exact exitance's image".to_string(),
    }
}

/// When the exact integral's current level started, to estimate what is left of it from the
/// receivers done so far, and whether it was already said that the level is long.
#[derive(Default)]
struct TruthClock {
    state: std::sync::Mutex<Option<(u32, std::time::Instant, bool)>>,
}

/// A level estimated to take longer than this is announced, with the options that cut it.
const LONG_TRUTH_LEVEL_SECONDS: f64 = 600.0;

impl TruthClock {
    /// Seconds left in `level` with `done` of `of` receivers finished (None before the first).
    /// The clock starts at the first receiver, not at the level's start: the sources placed
    /// before it are a fixed cost, which a rate per receiver would multiply.
    fn left(&self, level: u32, done: usize, of: usize) -> Option<f64> {
        if done == 0 {
            return None;
        }
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if state.is_none_or(|(l, _, _)| l != level) {
            *state = Some((level, std::time::Instant::now(), false));
        }
        let (_, start, _) = state.expect("set above");
        Some(start.elapsed().as_secs_f64() / done as f64 * of.saturating_sub(done) as f64)
    }

    /// The one line saying that `level` will take long, the first time its estimate says so.
    fn warning(&self, level: u32, left: Option<f64>) -> Option<String> {
        let left = left.filter(|&s| s > LONG_TRUTH_LEVEL_SECONDS)?;
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let (_, _, said) = state.as_mut().filter(|(l, _, said)| *l == level && !*said)?;
        *said = true;
        let stop = match level {
            0 => String::new(),
            l => format!("--truth-levels {} stops before it, ", l - 1),
        };
        Some(format!(
            "note: the exact integral's level {level} will take about {} more; {stop}--truth-receivers N \
             computes it at fewer vertices",
            human_duration(left)
        ))
    }
}

/// `95 s`, `12 min`, `3.4 h`.
fn human_duration(seconds: f64) -> String {
    match seconds {
        s if s < 120.0 => format!("{s:.0} s"),
        s if s < 7200.0 => format!("{:.0} min", s / 60.0),
        s => format!("{:.1} h", s / 3600.0),
    }
}

/// study.md's text above the results: the scene, device and timing method, then the truth
/// and its refinement level by level.
fn preamble(study: &study::Study, scene: &Scene, config: &StudyConfig, device: &str) -> String {
    let t = &study.truth;
    let mut levels = String::new();
    for l in &t.levels {
        levels += &format!(
            "| {} | {:.3} | {} | {} | {} | {:.1} |\n",
            l.level,
            l.eta,
            l.irradiance_points,
            l.change_rms.map_or("-".to_string(), |c| format!("{c:.2e}")),
            l.change_max.map_or("-".to_string(), |c| format!("{c:.2e}")),
            l.seconds
        );
    }
    let timing = if device.contains("llvmpipe") {
        "each pass in a submission of its own, submission to fence (isolated, as the committed studies were measured)"
    } else {
        "each pass in a submission of its own, submission to fence"
    };
    format!(
        "Scene `{}`, device {device}, {} configurations x seeds, the splat's visibility `{}` and shadow maps of \
         {}^2. Times: median of {} frames after one warm-up, a moving light's frame (splat, gather, shade), \
         {timing}.\n\n\
         Truth: the exact dipole integral at {} (`reference::truth`), {} (last change between levels \
         {:.2e} RMS relative over lit vertices; tolerance {:.0e}){}. Per-vertex errors are relative, over \
         vertices at least {:.0}% of the object's brightest in each channel.\n\n\
         | level | eta | E_t points | change RMS | change max | seconds |\n|---|---|---|---|---|---|\n{levels}",
        scene.name,
        config.runs() / config.seeds.len(),
        scene.file.render.splat_visibility,
        scene.file.render.shadow_map_size,
        config.frames,
        t.subset.map_or("every vertex".to_string(), |n| format!(
            "{n} vertices per object spread over the mesh (so no truth image and no image errors)"
        )),
        if t.converged { "converged" } else { "NOT converged" },
        t.change(),
        t.tolerance,
        if study.truth_cached { ", read from the cache" } else { "" },
        100.0 * truth::LIT_FLOOR,
    )
}

/// study.md's paragraph on the GPU against the f64 CPU reference, where it was timed.
fn reference_timing(study: &study::Study) -> String {
    study.reference.as_ref().map_or(String::new(), |t| {
        let r = &study.rows[t.row];
        format!(
            "\n\nGPU against the f64 CPU reference (`reference::splat` + `reference::gather`, the same sum in f64, \
             {} threads), {} {} vertex seed {}, same run: GPU frame {:.1} ms (splat + gather {:.1} ms), CPU {:.0} ms: \
             the GPU's splat and gather are {:.0}x faster.",
            t.threads,
            r.sampler,
            r.samples,
            r.seed,
            r.frame_ms,
            r.splat_ms + r.gather_ms,
            t.cpu_ms,
            t.cpu_ms / (r.splat_ms + r.gather_ms)
        )
    })
}

/// What a study writes into its folder, in [`write_outputs`]' order.
const OUTPUT_NAMES: [&str; 6] = ["study.csv", "study.md", "study.png", "truth.png", "error.png", "light.png"];

/// Write study.csv, study.md, study.png and light.png (`plots`: error against the truth and,
/// with `--physics`, against the light), truth.png (where the truth has an image) and
/// error.png (for `chosen`) into `output`, all or none (`OutputSet`).
fn write_outputs(
    output: &Path,
    study: &study::Study,
    chosen: Option<(Method, usize, Gather)>,
    md: String,
    (plot, light): (&[u8], Option<&[u8]>),
) -> Result<()> {
    let outputs: Vec<PathBuf> = OUTPUT_NAMES.iter().map(|n| output.join(n)).collect();
    let [w, h] = study.prepared.scene.file.camera.resolution;
    std::fs::create_dir_all(output).with_context(|| format!("cannot make {}", output.display()))?;
    let mut set = OutputSet::new();
    let text = |set: &mut OutputSet, path: &PathBuf, body: String| {
        set.stage(path, |tmp| {
            std::fs::write(tmp, body.as_bytes())
                .map_err(|source| translucent::output::OutputError::Io { path: path.clone(), source })
        })
    };
    text(&mut set, &outputs[0], report::csv(&study.rows))?;
    text(&mut set, &outputs[1], md)?;
    set.png(&outputs[2], 960, 640, plot)?;
    if let Some(light) = light {
        set.png(&outputs[5], 960, 640, light)?;
    }
    if let Some(image) = &study.truth_image {
        set.png(&outputs[3], w, h, &image.ldr)?;
    }
    if let Some((m, n, g)) = chosen {
        let i = study
            .rows
            .iter()
            .position(|r| {
                !r.default
                    && r.sampler == m.name()
                    && r.samples == n
                    && r.gather == g.0.name()
                    && r.epsilon == g.1.map(f64::from)
            })
            .expect("checked to be in the sweep");
        let estimate = study.exitance[i].as_ref().expect("not the pixel gather");
        let (rgba, width) = study::error_image(&study.prepared, &study.truth.exitance, estimate, 0.1)?;
        set.png(&outputs[4], width, h, &rgba)?;
    }
    for p in set.commit()? {
        out!("wrote {}", p.display());
    }
    Ok(())
}

fn report_plot(summaries: &[report::Summary], title: &str) -> Result<Vec<u8>> {
    translucent::study::plot::error_vs_time(summaries, title, 960, 640).map_err(anyhow::Error::msg)
}

#[cfg(test)]
mod tests {
    use super::TruthClock;

    /// The sources placed at a level's start are not a receiver's cost: an estimate taken
    /// right after the first receiver is near zero however long the start took.
    #[test]
    fn the_truth_clock_starts_at_the_first_receiver_not_at_the_levels_start() {
        let clock = TruthClock::default();
        assert!(clock.left(2, 0, 100).is_none(), "an estimate before any receiver");
        std::thread::sleep(std::time::Duration::from_millis(100));
        let left = clock.left(2, 1, 100).expect("an estimate after the first receiver");
        assert!(left < 1.0, "{left} s left: the sources' time was counted per receiver");
    }
}

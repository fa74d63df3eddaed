//! `translucent render [SCENE]`: render a scene (the built-in one without arguments) to PNG.

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::sync::Arc;
use translucent::SceneEdit;
use translucent::gpu::{Gpu, median};
use translucent::output::OutputSet;
use translucent::render::plan::{Change, Pass};
use translucent::render::renderer::Renderer;
use translucent::sampling::Method;
use translucent::scene::build::{Overrides, PreparedScene};
use translucent::scene::{GatherMode, Light, ReceiverPolicy, Scene, SplatVisibility, TransportMode, lights};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file (TOML, or a glTF 2.0 .gltf/.glb scene); the built-in marble bunny when omitted
    pub scene: Option<PathBuf>,
    /// Output PNG (tone-mapped sRGB)
    #[arg(short, long, default_value = "translucent.png")]
    pub output: PathBuf,
    /// Also write the linear HDR image as OpenEXR
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// Sample points per translucent object (overrides the scene and the error target)
    #[arg(long)]
    pub samples: Option<usize>,
    /// Relative per-vertex error against the exact dipole integral that each object's sample
    /// count is chosen for, e.g. 0.01 for 1% (overrides render.max_error)
    #[arg(long)]
    pub max_error: Option<f64>,
    /// Sampler (overrides the scene)
    #[arg(long, value_parser = super::one_of::<Method>(&Method::ALL.map(Method::name)))]
    pub sampler: Option<Method>,
    /// Where exitance is gathered: at every vertex, at every visible pixel, at the samples
    /// blended to the vertices, or at every vertex with far clusters of samples standing in for
    /// their members (overrides the scene)
    #[arg(long, value_parser = super::one_of::<GatherMode>(&GatherMode::ALL.map(GatherMode::name)))]
    pub gather: Option<GatherMode>,
    /// The hierarchical gather's accuracy knob, 0 to 10: a cluster of samples of area A whose
    /// nearest member is r away stands in for them when A < EPSILON r^2; 0 is the exact flat
    /// sum, larger is faster and coarser (overrides render.gather_epsilon)
    #[arg(long, value_name = "EPSILON", allow_negative_numbers = true)]
    pub gather_epsilon: Option<f32>,
    /// The texture gather's importance-sampled texels per receiver, 0 to 4096 (overrides
    /// render.texture_samples)
    #[arg(long, value_name = "N")]
    pub texture_samples: Option<u32>,
    /// The texture gather's atlas resolution in texels per side, 16 to 2048 (overrides
    /// render.texture_resolution)
    #[arg(long, value_name = "TEXELS")]
    pub texture_resolution: Option<u32>,
    /// Image size WIDTHxHEIGHT (overrides the scene)
    #[arg(long, value_parser = parse_resolution)]
    pub resolution: Option<[u32; 2]>,
    /// Frames to render; after the first, each frame recomputes what `--moving` invalidates
    #[arg(long, default_value_t = 1)]
    pub frames: u32,
    /// What each frame after the first recomputes
    #[arg(long, value_enum, default_value_t = Moving::Light)]
    pub moving: Moving,
    /// Submit each pass separately and time it from submission to fence (wall clock): the
    /// check on the timestamp figures
    #[arg(long)]
    pub isolate: bool,
    /// Print per-pass GPU milliseconds (median over the frames after the first)
    #[arg(long)]
    pub timings: bool,
    /// Print, for every frame rendered, which passes run and why, and each translucent
    /// object's choices per channel with the numbers behind them (as `translucent plan`)
    #[arg(long, alias = "plan")]
    pub explain: bool,
    /// Local or gathered exitance per channel: the planner's choice (auto), or forced
    /// (overrides render.transport)
    #[arg(long, value_parser = super::one_of::<TransportMode>(&TransportMode::ALL.map(TransportMode::name)))]
    pub transport: Option<TransportMode>,
    /// How the splat finds whether a light reaches a sample: shadow rays into the casters'
    /// triangles (exact) or one tap of the light's shadow map (overrides
    /// render.splat_visibility)
    #[arg(long, value_parser = super::one_of::<SplatVisibility>(&SplatVisibility::ALL.map(SplatVisibility::name)))]
    pub splat_visibility: Option<SplatVisibility>,
    /// Which receivers the hierarchical gather recomputes after a change: those the eye may see
    /// first and the rest over the next frames, or every one each time (overrides
    /// render.receivers)
    #[arg(long, value_parser = super::one_of::<ReceiverPolicy>(&ReceiverPolicy::ALL.map(ReceiverPolicy::name)))]
    pub receivers: Option<ReceiverPolicy>,
    /// Write each translucent vertex's world position and the RGB radiant exitance drawn there
    /// to a PLY: gathered channels as gathered, local ones as R_d,total E_t at the vertex
    /// (implies --full-detail: every vertex gathered)
    #[arg(long)]
    pub export_exitance: Option<PathBuf>,
    /// Draw, shadow and gather every mesh whole, at every vertex (overrides
    /// render.level_of_detail)
    #[arg(long)]
    pub full_detail: bool,
}

/// What changes between frames (`--moving`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Moving {
    /// The first non-environment light orbits 3 degrees a frame: its shadow maps, splat, gather, shade
    Light,
    /// As if every light changed: all shadow maps too
    Lights,
    /// The camera orbits the scene's centre 3 degrees a frame: shading only, plus the gather in
    /// pixel mode
    Camera,
}

impl Default for Args {
    fn default() -> Self {
        Args {
            scene: None,
            output: PathBuf::from("translucent.png"),
            exr: None,
            samples: None,
            max_error: None,
            sampler: None,
            gather: None,
            gather_epsilon: None,
            texture_samples: None,
            texture_resolution: None,
            resolution: None,
            frames: 1,
            moving: Moving::Light,
            isolate: false,
            timings: false,
            explain: false,
            transport: None,
            splat_visibility: None,
            receivers: None,
            export_exitance: None,
            full_detail: false,
        }
    }
}

/// Turn scene light `index` by `degrees` about the vertical axis through the scene's centre.
fn orbit_light(renderer: &mut Renderer, index: usize, degrees: f32) -> Result<()> {
    let scene = renderer.scene();
    let light = &scene.scene.file.lights[index];
    let moved = lights::orbit(light, scene.bounds.0, degrees).context("an environment light cannot orbit")?;
    Ok(renderer.edit(SceneEdit::Light { index, light: moved })?)
}

/// Turn the camera by `degrees` about the vertical axis through the scene's centre.
fn orbit_camera(renderer: &mut Renderer, degrees: f32) -> Result<()> {
    let camera = renderer.camera().orbited(renderer.scene().bounds.0, degrees);
    Ok(renderer.edit(SceneEdit::Camera(camera))?)
}

fn parse_resolution(s: &str) -> Result<[u32; 2], String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("{s:?} is not WIDTHxHEIGHT"))?;
    let parse = |v: &str| v.trim().parse::<u32>().ok().filter(|v| (1..=16384).contains(v));
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok([w, h]),
        _ => Err(format!("{s:?}: width and height must be 1 to 16384")),
    }
}

pub fn run(gpu_args: &super::GpuArgs, args: &Args) -> Result<()> {
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    let outputs = check_outputs(args)?;
    super::remove_on_interrupt(&outputs)?;
    let prepared = prepare(args)?;
    let gpu: Arc<Gpu> = Gpu::new(&gpu_args.options())?;
    eprintln!(
        "device: {} | {} vertices, {} samples ({}), {} lights ({} shadow maps)",
        gpu.info().name,
        prepared.vertex_count(),
        prepared.sample_count(),
        match prepared.scene.file.render.gather {
            GatherMode::Texture => "atlas texels".to_string(),
            _ => prepared.scene.file.sampling.method.to_string(),
        },
        prepared.lights.len(),
        prepared.shadow_layers
    );
    let mut renderer = Renderer::new(&gpu, prepared).context("creating GPU resources")?;
    let moving = moving_change(&renderer, args)?;
    let timed = run_frames(&mut renderer, args, moving)?;
    write_outputs(&renderer, args)?;
    if args.timings {
        print_timings(&renderer, args, &gpu, timed)?;
    }
    Ok(())
}

/// Every output path, distinct and writable, before any work: a render that cannot be written
/// is not started.
fn check_outputs(args: &Args) -> Result<Vec<&PathBuf>> {
    let outputs: Vec<&PathBuf> = std::iter::once(&args.output).chain(&args.exr).chain(&args.export_exitance).collect();
    for (i, a) in outputs.iter().enumerate() {
        if outputs[..i].contains(a) {
            bail!("{} is named as two outputs", a.display());
        }
    }
    for path in &outputs {
        translucent::output::check_destination(path)?;
    }
    Ok(outputs)
}

/// The scene (the file, or the built-in one) prepared with the command line's overrides.
fn prepare(args: &Args) -> Result<PreparedScene> {
    let scene = match &args.scene {
        Some(path) => Scene::load(path)?,
        None => Scene::builtin(),
    };
    let overrides = Overrides {
        samples: args.samples,
        max_error: args.max_error,
        sampler: args.sampler,
        gather: args.gather,
        gather_epsilon: args.gather_epsilon,
        texture_samples: args.texture_samples,
        texture_resolution: args.texture_resolution,
        resolution: args.resolution,
        transport: args.transport,
        splat_visibility: args.splat_visibility,
        receivers: args.receivers,
        // Exported exitance is every vertex's.
        level_of_detail: (args.full_detail || args.export_exitance.is_some()).then_some(false),
    };
    let spinner = super::progress::spinner().with_message(format!("preparing {} (meshes, sample points)", scene.name));
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    let prepared = PreparedScene::new(&scene, &overrides);
    spinner.finish_and_clear();
    let mut prepared = prepared?;
    super::attach_kernels(&mut prepared, None)?;
    if args.export_exitance.is_some() && prepared.scene.file.render.gather == GatherMode::Pixel {
        bail!(
            "--export-exitance needs exitance at the vertices, and the pixel gather computes it only at \
             visible pixels: use --gather vertex or sparse"
        );
    }
    Ok(prepared)
}

/// What `--moving` changes between frames.
fn moving_change(renderer: &Renderer, args: &Args) -> Result<Change> {
    Ok(match args.moving {
        Moving::Light => {
            let key = renderer.scene().scene.file.lights.iter().position(|l| !matches!(l, Light::Environment { .. }));
            match key {
                Some(i) => Change::Light(i),
                None if args.frames > 1 => bail!("--moving light: the scene has no directional, point or spot light"),
                None => Change::Lights,
            }
        }
        Moving::Lights => Change::Lights,
        Moving::Camera => Change::Camera,
    })
}

/// Per pass and in total, the milliseconds of every counted frame.
struct Timed {
    per_pass: Vec<(Pass, Vec<f64>)>,
    totals: Vec<f64>,
    /// Each counted frame's wall time: from the change to the frame's fence.
    wall: Vec<f64>,
}

/// Render `--frames` frames, the first of everything and each later one after `moving`; the
/// first is not counted when there are more (it builds everything and warms caches).
fn run_frames(renderer: &mut Renderer, args: &Args, moving: Change) -> Result<Timed> {
    let progress = if args.frames > 1 {
        super::progress::bar(args.frames as u64)
            .with_style(ProgressStyle::with_template("frames {bar:30} {pos}/{len} {elapsed}").unwrap())
    } else {
        ProgressBar::hidden()
    };
    let mut timed = Timed { per_pass: Vec::new(), totals: Vec::new(), wall: Vec::new() };
    for frame in 0..args.frames {
        let start = std::time::Instant::now();
        let change = if frame == 0 { Change::Everything } else { moving };
        match change {
            Change::Light(i) => orbit_light(renderer, i, 3.0)?,
            Change::Camera => orbit_camera(renderer, 3.0)?,
            _ => {}
        }
        let plan = renderer.plan(change);
        if args.explain {
            eprintln!("frame {frame} (change: {change}):\n{}", plan.to_string().trim_end());
        }
        let timings = if args.isolate { renderer.frame_isolated(&plan)? } else { renderer.frame(&plan)? };
        if frame > 0 || args.frames == 1 {
            timed.wall.push(start.elapsed().as_secs_f64() * 1e3);
            timed.totals.push(timings.total());
            for (pass, ms) in timings.passes {
                match timed.per_pass.iter_mut().find(|(p, _)| *p == pass) {
                    Some((_, v)) => v.push(ms),
                    None => timed.per_pass.push((pass, vec![ms])),
                }
            }
        }
        progress.inc(1);
    }
    progress.finish_and_clear();
    Ok(timed)
}

/// An error naming where non-finite values came from, if the last frame had any. Checked on
/// every render, not only when a pixel shows it: a NaN clamped to black on the way is still a
/// NaN upstream.
fn check_finite(renderer: &Renderer, non_finite: u32) -> Result<()> {
    let upstream = renderer.find_non_finite()?;
    if non_finite == 0 && upstream.is_empty() {
        return Ok(());
    }
    let causes: Vec<String> = upstream
        .iter()
        .map(|n| {
            let o = &renderer.scene().objects[n.object];
            let what = if n.pass == Pass::Splat { "samples" } else { "vertices" };
            let pass = n.pass.name();
            format!("the {pass} pass left {} {what} of object[{}] ({}) non-finite", n.count, n.object, o.name)
        })
        .collect();
    let cause = if causes.is_empty() { "the shade pass produced them".to_string() } else { causes.join("; ") };
    bail!("{non_finite} pixels were NaN or infinite before tone mapping ({cause}); no output written");
}

/// The PNG, and the EXR and exitance PLY when asked for: each written to a temporary file
/// first and renamed only once all were written.
fn write_outputs(renderer: &Renderer, args: &Args) -> Result<()> {
    let (rgba8, non_finite) = renderer.image()?;
    check_finite(renderer, non_finite)?;
    let [width, height] = renderer.scene().scene.file.camera.resolution;
    let mut outputs = OutputSet::new();
    outputs.png(&args.output, width, height, &rgba8)?;
    if let Some(exr) = &args.exr {
        outputs.exr(exr, width, height, &renderer.hdr_image()?)?;
    }
    let mut exported = 0;
    if let Some(ply) = &args.export_exitance {
        let mut points = Vec::new();
        for (i, o) in renderer.scene().objects.iter().enumerate() {
            if o.samples.is_empty() {
                continue;
            }
            for (p, e) in o.mesh.positions().iter().zip(renderer.exitance_drawn(i)?) {
                points.push((p.to_array(), e));
            }
        }
        outputs.exitance_ply(ply, &points)?;
        exported = points.len();
    }
    for path in outputs.commit()? {
        if Some(&path) == args.export_exitance.as_ref() {
            eprintln!("wrote {} ({exported} vertices)", path.display());
        } else {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}

/// `--timings`: the median of each pass and of the frame, and the device memory in use.
fn print_timings(renderer: &Renderer, args: &Args, gpu: &Gpu, timed: Timed) -> Result<()> {
    let Timed { per_pass, mut totals, mut wall } = timed;
    let frames = totals.len();
    let how = if args.isolate { "submission-to-fence wall time" } else { "GPU time (timestamp queries)" };
    let after = if args.frames > 1 { " after the first" } else { "" };
    out!("{how} per pass on {} (median of {frames} frame(s){after}):", gpu.info().name);
    for (pass, mut v) in per_pass {
        out!("  {:<8} {:>9.3} ms", pass.name(), median(&mut v));
    }
    let total = median(&mut totals);
    out!("  {:<8} {:>9.3} ms  ({:.1} frames/s)", "total", total, 1000.0 / total);
    // What an application waits for: the change applied, planned, recorded, submitted and
    // finished (the first frame's build excluded as above).
    let wall = median(&mut wall);
    out!("  {:<8} {:>9.3} ms  ({:.1} frames/s; the change, plan, recording and fence)", "wall", wall, 1000.0 / wall);
    out!("device memory in use: {:.1} MiB", renderer.device_memory() as f64 / (1 << 20) as f64);
    Ok(())
}

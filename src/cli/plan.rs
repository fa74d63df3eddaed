//! `translucent plan [SCENE] [--json]`: what each kind of frame change would run for a scene,
//! per pass and per object and channel, with the reason and the numbers behind each choice. No
//! GPU is needed: planning is CPU work over the prepared scene.

use anyhow::Result;
use std::path::PathBuf;
use translucent::mesh::atlas::{Atlas, AtlasSource};
use translucent::render::camera::CameraView;
use translucent::render::plan::{self, Change, Planner};
use translucent::scene::build::{Overrides, PreparedScene};
use translucent::scene::{GatherMode, Scene, TransportMode};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file (TOML, or a glTF 2.0 .gltf/.glb scene); the built-in marble bunny when omitted
    pub scene: Option<PathBuf>,
    /// Print JSON (the shape docs/PLAN.md documents) instead of text
    #[arg(long)]
    pub json: bool,
    /// Sample points per translucent object (overrides the scene)
    #[arg(long)]
    pub samples: Option<usize>,
    /// Where exitance is gathered (overrides the scene)
    #[arg(long, value_parser = super::one_of::<GatherMode>(&GatherMode::ALL.map(GatherMode::name)))]
    pub gather: Option<GatherMode>,
    /// Local or gathered exitance per channel: the planner's choice, or forced (overrides
    /// render.transport)
    #[arg(long, value_parser = super::one_of::<TransportMode>(&TransportMode::ALL.map(TransportMode::name)))]
    pub transport: Option<TransportMode>,
    /// Relative per-vertex error against the exact dipole integral that each object's sample
    /// count is chosen for, e.g. 0.01 for 1% (overrides render.max_error)
    #[arg(long)]
    pub max_error: Option<f64>,
}

pub fn run(args: &Args) -> Result<()> {
    let scene = match &args.scene {
        Some(path) => Scene::load(path)?,
        None => Scene::builtin(),
    };
    let overrides = Overrides {
        samples: args.samples,
        gather: args.gather,
        transport: args.transport,
        max_error: args.max_error,
        ..Overrides::default()
    };
    let mut prepared = PreparedScene::new(&scene, &overrides)?;
    super::attach_kernels(&mut prepared, None)?;
    let objects = prepared.objects.len();
    let mut planner = Planner::new(objects, Change::Everything);
    let needs = plan::needs(&prepared, false, planner.baked_levels());
    let view = plan::View::of_camera(&CameraView::of_scene(&prepared), prepared.scene.file.camera.resolution[1]);
    // The first frame computes everything; every other change follows a frame that did, at the
    // levels of detail it chose (a fresh scene has no levels baked from sky light to withdraw).
    let first = planner.plan(&needs, &view);
    planner.recorded(
        &first,
        matches!(
            prepared.scene.file.render.gather,
            GatherMode::Vertex | GatherMode::Hierarchical | GatherMode::Texture
        ),
    );
    let mut frames: Vec<(Change, plan::Plan)> = Change::all(prepared.scene.file.lights.len(), objects)
        .into_iter()
        .map(|change| {
            (change, if change == Change::Everything { first.clone() } else { planner.plan_for(&needs, &view, change) })
        })
        .collect();
    count_seen(&prepared, &view, &mut frames);
    if args.json {
        let json = serde_json::json!({
            "scene": prepared.scene.name,
            "version": 1,
            "objects": needs.objects,
            "frames": frames.iter().map(|(_, p)| p.to_json()).collect::<Vec<_>>(),
            "atlases": atlases(&prepared).map(|(object, a)| serde_json::json!({
                "object": object,
                "source": match a.source { AtlasSource::OwnUvs => "own_uvs", AtlasSource::Charts(_) => "charts" },
                "why": match a.source { AtlasSource::OwnUvs => None, AtlasSource::Charts(why) => Some(why.to_string()) },
                "resolution": a.resolution,
                "texels": a.texels.len(),
                "charts": a.charts,
            })).collect::<Vec<_>>(),
        });
        out!("{}", serde_json::to_string_pretty(&json)?);
        return Ok(());
    }
    out!("{}: {} objects, {} lights", prepared.scene.name, objects, prepared.scene.file.lights.len());
    for (i, atlas) in atlases(&prepared) {
        let (side, used) = (atlas.resolution, atlas.texels.len());
        let share = 100.0 * used as f64 / f64::from(side * side);
        out!("object {i}: texture atlas {side}x{side} from {}: {used} texels ({share:.1}% used)", atlas.source);
    }
    for (change, p) in &frames {
        out!("after a change of {change}:");
        out!("{}", p.to_string().trim_end());
    }
    Ok(())
}

/// The texture gather's atlas of each object that has one, with the object's index.
fn atlases(prepared: &PreparedScene) -> impl Iterator<Item = (usize, &Atlas)> {
    prepared.objects.iter().enumerate().filter_map(|(i, o)| o.atlas.as_deref().map(|a| (i, a)))
}

/// Each gathered object's receivers an eye may see, counted on the host as the GPU picks them
/// (`receiver_view::seen_receivers`), and for an object a transport kernel scales those its
/// patches add (`receiver_view::kernel_gathered`), in every plan that gathers visible-first;
/// counted once per level.
fn count_seen(prepared: &PreparedScene, view: &plan::View, frames: &mut [(Change, plan::Plan)]) {
    use translucent::render::plan::ReceiverScope;
    use translucent::render::receiver_view::{kernel_gathered, seen_receivers};
    use translucent::render::target::DepthConvention;
    use translucent::scene::needs::KernelState;
    let mut counted = std::collections::HashMap::new();
    for o in frames.iter_mut().flat_map(|(_, p)| p.objects.iter_mut()) {
        if !o.gather || !matches!(o.receivers, ReceiverScope::VisibleFirst { .. }) {
            continue;
        }
        let object = &prepared.objects[o.object];
        let (seen, more) = *counted.entry((o.object, o.level)).or_insert_with(|| {
            let of = object.levels.get(o.level).map_or(0, |l| l.vertices.len());
            let seen = seen_receivers(object, o.level, view, DepthConvention::Standard);
            let kernel = o.transport.is_some_and(|t| matches!(t, KernelState::Scales { .. }));
            let more = kernel.then(|| kernel_gathered(object, o.level, &seen).len() - seen.len());
            ([seen.len(), of], more)
        });
        o.receivers_seen = Some(seen);
        o.receivers_for_kernel = more;
    }
}

//! The "receivers" section: the hierarchical gather recomputing the receivers an eye may see
//! first (`render.receivers = "visible_first"`, the default) against every receiver, on the
//! default scene at 512x512, renderers stepped side by side (alternating, so outside load falls
//! on both alike), GPU timestamps; then the frame with one of the 17 lights moving against one
//! with all of them changed; then the gather's time against the share of the mesh an eye may
//! see, the camera zoomed in at the level of detail the default view draws; then the same with
//! the bunny's transport kernel attached (what `model = "auto"` draws), whose pick adds every
//! vertex of the patches the seen ones blend.

use super::{FRAMES, WARM_UP, step};
use glam::{Mat4, Vec3};
use std::sync::Arc;
use translucent::SceneEdit;
use translucent::gpu::{Gpu, median};
use translucent::render::plan::{Change, Pass, SWEEP_FRAMES};
use translucent::render::receiver_view::GATHER;
use translucent::render::renderer::Renderer;
use translucent::scene::build::{Overrides, PreparedScene};
use translucent::scene::{ReceiverPolicy, Scene};

/// Light-moving frames per renderer after the warm-up: the two rows alternate.
const RECEIVER_FRAMES: usize = 3 * FRAMES;

fn renderer(gpu: &Arc<Gpu>, policy: ReceiverPolicy) -> Renderer {
    super::default_renderer(gpu, Overrides { receivers: Some(policy), ..Overrides::default() })
}

/// The default scene at 512x512 with the bunny's transport kernel attached (read from the
/// cache, or walked there first), its receivers under `policy`.
fn kernel_renderer(gpu: &Arc<Gpu>, policy: ReceiverPolicy) -> Renderer {
    use translucent::reference::{rte_mesh::KernelSettings, transport_cache, truth};
    let overrides = Overrides { receivers: Some(policy), resolution: Some([512, 512]), ..Overrides::default() };
    let mut prepared = PreparedScene::new(&Scene::builtin(), &overrides).expect("default scene");
    let dir = truth::default_cache_dir();
    transport_cache::attach(&mut prepared.objects, &KernelSettings::default(), &dir, &|_, _, _| {})
        .expect("transport kernel");
    assert!(prepared.objects[0].transport.is_some(), "model = \"auto\" takes the bunny's kernel");
    let mut renderer = Renderer::new(gpu, prepared).expect("renderer");
    renderer.frame(&renderer.plan(Change::Everything)).expect("first frame");
    renderer
}

/// Median gather and frame time by timestamps of each renderer, stepped side by side through
/// `frames` frames of `change` after the warm-up, each at `level` if given; and whether every
/// frame's image was the same in all of them.
fn side_by_side(rows: &mut [Renderer], change: Change, frames: usize, level: Option<usize>) -> (Vec<[f64; 2]>, bool) {
    let mut times = vec![(Vec::new(), Vec::new()); rows.len()];
    let mut same = true;
    for frame in 0..WARM_UP + frames {
        let mut images = Vec::new();
        for (r, (gather, total)) in rows.iter_mut().zip(&mut times) {
            // All lights changed is planned as such, with nothing moved.
            if change != Change::Lights {
                step(r, change);
            }
            let mut plan = r.plan(change);
            if let Some(level) = level {
                plan.objects.iter_mut().filter(|o| !o.channels.is_empty()).for_each(|o| o.level = level);
            }
            let timings = r.frame(&plan).expect("frame");
            images.push(r.image().expect("image").0);
            if frame >= WARM_UP {
                gather.push(timings.get(Pass::Gather).unwrap_or(0.0));
                total.push(timings.total());
            }
        }
        same &= images.windows(2).all(|w| w[0] == w[1]);
    }
    (times.iter_mut().map(|(g, t)| [median(g), median(t)]).collect(), same)
}

/// Share of object 0's receivers at its level the last frame's pick marked to gather.
fn picked_share(r: &Renderer, level: usize) -> f64 {
    let state: Vec<[u32; 2]> = r.scene_data().buffers().receiver_state().read().expect("receiver state");
    let level = &r.scene().objects[0].levels[level];
    let gathered = level.vertices.iter().filter(|&&v| state[v as usize][1] & GATHER != 0).count();
    gathered as f64 / level.vertices.len() as f64
}

pub fn receivers(gpu: &Arc<Gpu>) {
    let mut rows = [renderer(gpu, ReceiverPolicy::Every), renderer(gpu, ReceiverPolicy::VisibleFirst)];
    let level = rows[1].plan(Change::Camera).objects[0].level;
    println!(
        "\nReceivers, default scene 512x512, key light moving, timestamps (median of {RECEIVER_FRAMES} after \
         {WARM_UP} warm-up), side by side:"
    );
    let (m, same) = side_by_side(&mut rows, Change::Light(0), RECEIVER_FRAMES, None);
    println!("  {:<16} {:>10} {:>10} {:>9}", "receivers", "gather ms", "frame ms", "frames/s");
    for (name, [gather, total]) in ["every", "visible_first"].iter().zip(&m) {
        println!("  {name:<16} {gather:>10.2} {total:>10.2} {:>9.1}", 1000.0 / total);
    }
    println!(
        "  visible_first / every: gather {:.2}x, frame {:.2}x; {:.0}% of the level's receivers picked; every image \
         the same: {same}",
        m[1][0] / m[0][0],
        m[1][1] / m[0][1],
        100.0 * picked_share(&rows[1], level)
    );

    // The camera frames after the light stops: the sweep's chunks, then nothing to gather.
    let (sweep, _) = side_by_side(&mut rows, Change::Camera, SWEEP_FRAMES as usize - WARM_UP, None);
    let (after, _) = side_by_side(&mut rows, Change::Camera, FRAMES, None);
    println!("\nCamera frames after the light stops (frame by timestamps; gather ms in brackets):");
    println!("  {:<16} {:>22} {:>22}", "receivers", "the sweep's frames", "after it");
    for (name, (s, a)) in ["every", "visible_first"].iter().zip(sweep.iter().zip(&after)) {
        println!("  {name:<16} {:>13.2} ({:>5.2}) {:>15.2} ({:>4.2})", s[1], s[0], a[1], a[0]);
    }

    // Both rows step, so that their lights stay where the other's are.
    let (one, _) = side_by_side(&mut rows, Change::Light(0), FRAMES, None);
    let (all, _) = side_by_side(&mut rows, Change::Lights, FRAMES, None);
    println!(
        "\nOne of the {} lights moving against all of them changed (frame by timestamps):",
        rows[0].scene().lights.len()
    );
    for (name, (one, all)) in ["every", "visible_first"].iter().zip(one.iter().zip(&all)) {
        println!("  {name:<16} {:.1} against {:.1} ms = {:.2}x", one[1], all[1], one[1] / all[1]);
    }

    println!(
        "\nGather against the share of the mesh an eye may see (camera zoomed in, level {level}, key light moving):"
    );
    zoomed(&mut rows, level, &[1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 10.0, 16.0]);

    let mut kernel = [kernel_renderer(gpu, ReceiverPolicy::Every), kernel_renderer(gpu, ReceiverPolicy::VisibleFirst)];
    println!(
        "\nThe same with the bunny's transport kernel (model = \"auto\"; the gather's slot includes the transport \
         pass), level {level}, key light moving:"
    );
    zoomed(&mut kernel, level, &[1.0, 4.0, 6.0]);
}

/// The gather by timestamps of `rows` (every receiver, then visible first) at each of `zooms`,
/// side by side at `level`, with the share of the level's receivers the second gathered.
fn zoomed(rows: &mut [Renderer; 2], level: usize, zooms: &[f32]) {
    println!(
        "  {:>6} {:>8} {:>16} {:>20} {:>7} {:>12}",
        "zoom", "share", "every gather ms", "visible_first ms", "ratio", "frame ratio"
    );
    let camera = rows[0].camera();
    for &zoom in zooms {
        let zoomed = translucent::render::camera::CameraView {
            projection: Mat4::from_scale(Vec3::new(zoom, zoom, 1.0)) * camera.projection,
            ..camera
        };
        for r in rows.iter_mut() {
            r.edit(SceneEdit::Camera(zoomed)).expect("camera");
        }
        let (m, same) = side_by_side(rows, Change::Light(0), FRAMES, Some(level));
        assert!(same, "visible-first images differ from every receiver's at zoom {zoom}");
        let share = picked_share(&rows[1], level);
        let ratio = [m[1][0] / m[0][0], m[1][1] / m[0][1]];
        println!("  {zoom:>6.1} {share:>8.2} {:>16.2} {:>20.2} {:>7.2} {:>12.2}", m[0][0], m[1][0], ratio[0], ratio[1]);
    }
}

//! The between-points single scattering in the renderer (`glsl/beam_gather.comp`) against its
//! f64 twin: the same table (`optics::beam_table`) read in f64 over the same walk of the sample
//! hierarchy, clusters standing in for their members as `render.beam_opening` says, with the
//! density correction, per vertex; the cut against the sum over every sample; the channels the
//! material's `model` leaves to the dipole untouched; and an object whose records come after
//! another's.

mod common;

use glam::DVec3;
use translucent::optics::beam_table::BeamTable;
use translucent::optics::directional_dipole::refract_in;
use translucent::render::beam_gather::{ObjectBeams, WalkItem, object_tables, pack_tables, walk};
use translucent::render::plan::Change;
use translucent::render::renderer::Renderer;
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedObject, PreparedScene};

/// The light's direction towards it.
const LIGHT: [f64; 3] = [0.8, 0.5, 0.3];

/// A 2 cm sphere of ketchup (1 unit = 1 mm) with `model`, under one directional light.
fn ketchup(model: &str) -> PreparedScene {
    let text = format!(
        r#"
[camera]
eye = [0.0, 12.0, 45.0]
target = [0.0, 0.0, 0.0]
resolution = [32, 32]

[[object]]
shape = {{ type = "sphere", radius = 10.0, divisions = 12 }}
material = {{ type = "translucent", preset = "ketchup", mm_per_unit = 1.0, model = "{model}" }}
casts_shadow = false

[[light]]
type = "directional"
direction = {LIGHT:?}
irradiance = [1.0, 1.0, 1.0]

[sampling]
count = 3000
"#
    );
    PreparedScene::new(&Scene::parse(&text, "test.toml", None).unwrap(), &Overrides::default()).unwrap()
}

/// What one frame of a scene gives the tests of one object.
struct Frame {
    /// The vertices it was gathered at (object-relative, ascending; every vertex at level 0).
    vertices: Vec<u32>,
    /// Their exitance, in the same order.
    exitance: Vec<[f32; 3]>,
    /// The splat's transmitted irradiance per sample of the object.
    splat: Vec<[f32; 3]>,
    /// The plan as `plan` prints it.
    plan: String,
}

/// One full frame, every object at level 0 but `object` at `level`.
fn frame_of(prepared: PreparedScene, object: usize, level: usize) -> Frame {
    let first_sample: usize = prepared.objects[..object].iter().map(|o| o.samples.len()).sum();
    common::with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, prepared).unwrap();
        let mut plan = renderer.plan(Change::Everything);
        plan.objects.iter_mut().for_each(|o| o.level = 0);
        plan.objects.iter_mut().filter(|o| o.object == object).for_each(|o| o.level = level);
        renderer.frame(&plan).unwrap();
        let splat = renderer.splat_irradiance().unwrap().into_iter().skip(first_sample).map(|(e, _)| e).collect();
        let at = renderer.exitance_at_level(object).unwrap();
        assert_eq!(at.level, level);
        Frame { vertices: at.vertices, exitance: at.values, splat, plan: plan.to_string() }
    })
}

/// [`frame_of`] object 0 at every vertex.
fn frame(prepared: PreparedScene) -> Frame {
    frame_of(prepared, 0, 0)
}

/// The worst difference of `f`'s exitance (object `o`'s) from the f64 twin at `opening` in
/// green and blue and, `with_cut`, the worst of the twin at `opening` from the flat sum (0
/// otherwise), both as a share of the brightest vertex.
fn against_twin(o: &PreparedObject, f: &Frame, opening: f32, with_cut: bool) -> (f64, f64) {
    let (beams, tables) = object_tables(o, 1, opening).unwrap();
    let positions = o.mesh.positions();
    let brightest = f.exitance.iter().map(|m| m[1].max(m[2])).fold(0.0f32, f32::max);
    assert!(brightest > 0.0);
    let (mut worst, mut cut) = (0.0f64, 0.0f64);
    for (&v, m) in f.vertices.iter().zip(&f.exitance) {
        assert!(m.iter().all(|x| x.is_finite() && *x >= 0.0), "vertex {v}: {m:?}");
        let x = positions[v as usize].as_dvec3();
        for c in [1, 2] {
            let at = |opening| twin(o, &beams, tables[c].as_ref().unwrap(), c, &f.splat, x, opening);
            let expect = at(f64::from(beams.opening));
            worst = worst.max((f64::from(m[c]) - expect).abs() / f64::from(brightest));
            if with_cut {
                // What the clusters cost: the same twin over every sample within reach.
                cut = cut.max((expect - at(0.0)).abs() / f64::from(brightest));
            }
        }
    }
    (worst, cut)
}

/// What enters at one point or node: position, unit normal, unit beam, summed `A E` in the
/// channel, summed `A`.
struct Entry {
    p: DVec3,
    n: DVec3,
    w: DVec3,
    power: f64,
    area: f64,
}

/// The f64 twin of glsl/beam_gather.comp at vertex `x` in channel `c`: the walk of the object's
/// hierarchy (`beam_gather::walk`) with nodes under `opening` of their distance (or of the
/// window) standing in for their members, the entries' `A E T` against their `A T(rho, 1, 1)`
/// (summed here, not read from `receiver_walks`), times `R1(1)`.
fn twin(
    o: &PreparedObject,
    beams: &ObjectBeams,
    table: &BeamTable,
    c: usize,
    splat: &[[f32; 3]],
    x: DVec3,
    opening: f64,
) -> f64 {
    let tree = o.sample_tree();
    let (mut sum, mut norm) = (0.0, 0.0);
    let mut add = |e: Entry| {
        let d = x - e.p;
        let dist = d.length();
        if dist >= f64::from(beams.reach) {
            return;
        }
        let mu = (-e.w.dot(e.n)).clamp(0.0, 1.0);
        let (dt, wt) = (d - d.dot(e.n) * e.n, e.w + mu * e.n);
        let len = dt.length() * wt.length();
        let cos_phi = if len > 0.0 { dt.dot(wt) / len } else { 1.0 };
        let sigma = f64::from(beams.sigma_t[c]);
        let rho = dist * sigma;
        sum += e.power * table.lookup(rho, cos_phi, mu);
        norm += e.area * table.lookup(rho, 1.0, 1.0);
    };
    let beams = ObjectBeams { opening: opening as f32, ..*beams };
    walk(&tree, x, &beams, |item| match item {
        WalkItem::Node(i) => {
            let n = &tree.nodes[i];
            add(node_entry(o, &tree.order[n.first as usize..(n.first + n.count) as usize], splat, c));
        }
        WalkItem::Sample(s) => add(sample_entry(o, s, splat, c)),
    });
    if norm > 0.0 { table.normal_total * sum / norm } else { 0.0 }
}

/// Sample `s` as the splat leaves it: its beam is the light's refracted direction where the
/// light reaches it, the inward normal elsewhere.
fn sample_entry(o: &PreparedObject, s: usize, splat: &[[f32; 3]], c: usize) -> Entry {
    let sample = &o.samples[s];
    let (p, n) = (sample.position.as_dvec3(), sample.normal.as_dvec3());
    let lit = splat[s].iter().any(|&e| e > 0.0);
    let w = if lit { refract_in(DVec3::from(LIGHT).normalize(), n, eta_of(o)).unwrap() } else { -n };
    Entry { p, n, w, power: sample.area * f64::from(splat[s][c]), area: sample.area }
}

/// A node's members as one entry: summed power and area at their area-weighted centroid, their
/// mean normal, their beams' mean weighted by power summed over channels.
fn node_entry(o: &PreparedObject, members: &[u32], splat: &[[f32; 3]], c: usize) -> Entry {
    let (mut p, mut n, mut w, mut power, mut area) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO, 0.0, 0.0);
    for &s in members {
        let e = sample_entry(o, s as usize, splat, c);
        let total: f64 = splat[s as usize].iter().map(|&v| e.area * f64::from(v)).sum();
        (p, n, w) = (p + e.area * e.p, n + e.area * e.n, w + total * e.w);
        (power, area) = (power + e.power, area + e.area);
    }
    let (n, p) = (n.normalize_or(DVec3::Z), p / area);
    Entry { p, n, w: w.try_normalize().unwrap_or(-n), power, area }
}

fn eta_of(o: &PreparedObject) -> f64 {
    match &o.material {
        translucent::scene::build::ResolvedMaterial::Translucent { dipoles, .. } => dipoles[0].eta,
        _ => unreachable!("the sphere is translucent"),
    }
}

#[test]
fn the_gpu_between_points_sum_matches_its_f64_twin_and_leaves_the_dipoles_channels_alone() {
    let auto = ketchup("auto");
    let object = auto.objects[0].clone();
    // Ketchup's red has alpha' 0.75, green and blue 0.067 and 0.020: `auto` gives them to
    // single scattering between points.
    assert_eq!(object.single_channels(), [false, true, true]);
    let ours_frame = frame(auto);
    let (ours, plan) = (&ours_frame.exitance, &ours_frame.plan);
    let dipole_frame = frame(ketchup("dipole"));
    let (dipole, plain) = (&dipole_frame.exitance, &dipole_frame.plan);
    // The plan says which channels take the model and why; the dipole's plan says nothing of it.
    assert!(plan.contains("G single scattering between points") && plan.contains("B single scattering"), "{plan}");
    assert!(!plan.contains("R single") && !plain.contains("single scattering"), "{plan}\n{plain}");
    for (v, (m, d)) in ours.iter().zip(dipole).enumerate() {
        // The dipole's channel is what the dipole gather wrote, bit for bit.
        assert_eq!(m[0].to_bits(), d[0].to_bits(), "vertex {v}: red {} against the dipole's {}", m[0], d[0]);
    }
    let (worst, cut) = against_twin(&object, &ours_frame, translucent::scene::DEFAULT_BEAM_OPENING, true);
    eprintln!(
        "worst difference from the f64 twin: {worst:.2e} of the brightest vertex; the cut from the flat sum: {cut:.2e}"
    );
    assert!(worst < 1e-3, "the GPU sum is {worst:.2e} of the brightest vertex from its f64 twin");
    // At the default opening the clusters stand in for their members within 1% of the
    // brightest vertex (0.26% measured).
    assert!(cut < 0.01, "the cut is {cut:.2e} of the brightest vertex from the sum over every sample");
    // Green and blue are the model's, not the dipole's: they differ at some vertex.
    assert!(ours.iter().zip(dipole).any(|(m, d)| (m[1] - d[1]).abs() > 0.05 * d[1].abs().max(1e-6)));
}

#[test]
fn an_object_after_another_walks_its_own_hierarchy_and_stand_ins() {
    // A dipole sphere first, so the model's object has its nodes, samples and stand-ins after
    // another's in the shared buffers.
    let sphere = |x: f32, model: &str| {
        format!(
            r#"
[[object]]
shape = {{ type = "sphere", radius = 10.0, divisions = 12 }}
transform = {{ translate = [{x:?}, 0.0, 0.0] }}
material = {{ type = "translucent", preset = "ketchup", mm_per_unit = 1.0, model = "{model}" }}
casts_shadow = false
"#
        )
    };
    let text = format!(
        r#"
[camera]
eye = [0.0, 12.0, 120.0]
target = [0.0, 0.0, 0.0]
resolution = [32, 32]
{}{}
[[light]]
type = "directional"
direction = {LIGHT:?}
irradiance = [1.0, 1.0, 1.0]

[sampling]
count = 3000
"#,
        sphere(-30.0, "dipole"),
        sphere(30.0, "auto")
    );
    let prepared = PreparedScene::new(&Scene::parse(&text, "two.toml", None).unwrap(), &Overrides::default()).unwrap();
    let object = prepared.objects[1].clone();
    let (worst, _) = against_twin(&object, &frame_of(prepared, 1, 0), translucent::scene::DEFAULT_BEAM_OPENING, false);
    eprintln!("second object: worst difference from the f64 twin {worst:.2e} of its brightest vertex");
    assert!(worst < 1e-3, "the second object's sum is {worst:.2e} of its brightest vertex from its f64 twin");
}

#[test]
fn walks_read_from_the_upload_give_the_same_sums_as_walks_taken_each_frame_at_every_level() {
    let mut walked = ketchup("auto");
    walked.scene.file.render.beam_walk_mib = 0;
    let levels = walked.objects[0].levels.len();
    assert!(levels > 1, "the test sphere has coarser levels of detail");
    let object = walked.objects[0].clone();
    // One path each: the default budget keeps the walks, 0 keeps none.
    let lists = |p: &PreparedScene| pack_tables(p, &[]).beams[0].unwrap().lists;
    assert!(lists(&ketchup("auto")) && !lists(&walked));
    for level in [0, levels - 1] {
        let each_frame = frame_of(walked.clone(), 0, level);
        let read = frame_of(ketchup("auto"), 0, level);
        assert_eq!(each_frame.vertices, read.vertices);
        // The same sources in the same order: the same sums, bit for bit.
        for (v, (a, b)) in each_frame.exitance.iter().zip(&read.exitance).enumerate() {
            assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "level {level}, vertex {}", read.vertices[v]);
        }
        // And at a coarser level, its vertices' sums are the twin's at those vertices.
        let (worst, _) = against_twin(&object, &read, translucent::scene::DEFAULT_BEAM_OPENING, false);
        assert!(worst < 1e-3, "level {level}: {worst:.2e} of the brightest vertex from the twin");
    }
}

/// The error of a ketchup sphere with `model = "auto"` whose `[render]` holds `line`, parsed as
/// file `name`.
fn render_error(line: &str, name: &str) -> String {
    let text = format!(
        r#"
[camera]
eye = [0.0, 12.0, 45.0]
target = [0.0, 0.0, 0.0]

[[object]]
shape = {{ type = "sphere", radius = 10.0, divisions = 12 }}
material = {{ type = "translucent", preset = "ketchup", mm_per_unit = 1.0, model = "auto" }}

[render]
{line}
"#
    );
    Scene::parse(&text, name, None).expect_err("refused").to_string()
}

#[test]
fn a_beam_opening_out_of_range_is_an_error_naming_the_key_and_its_limit() {
    let err = render_error("beam_opening = 0.9", "opening.toml");
    assert!(
        err.contains("render.beam_opening") && err.contains("must be 0 to 0.5") && err.contains("opening.toml"),
        "{err}"
    );
}

#[test]
fn a_walk_budget_past_its_limit_is_an_error_naming_the_key() {
    let err = render_error("beam_walk_mib = 5000", "walks.toml");
    assert!(err.contains("render.beam_walk_mib") && err.contains("0 to 4095") && err.contains("walks.toml"), "{err}");
}

#[test]
fn a_between_points_model_with_the_pixel_gather_is_refused_with_the_key_to_change() {
    let mut prepared = ketchup("auto");
    prepared.scene.file.render.gather = translucent::scene::GatherMode::Pixel;
    let err = common::with_gpu(|gpu| Renderer::new(gpu, prepared).err().expect("refused").to_string());
    assert!(err.contains("material.model") && err.contains("render.gather"), "{err}");
}

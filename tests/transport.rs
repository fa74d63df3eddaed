//! The transport kernel (`material.model = "transport"`, `optics::transport`): its walks against
//! the half-space's closed answer and energy, the GPU pass (`glsl/transport.comp`) against its
//! f64 twin, its cache refusing what it cannot trust, and a cached kernel under a moving light
//! against the RTE.

mod common;

use glam::DVec3;
use translucent::optics::transport::{SampleFlux, TransportKernel};
use translucent::reference::rte::{Budget, Medium, half_space_reflectance};
use translucent::reference::rte_mesh::{KernelSettings, object_kernel, object_kernel_walks};
use translucent::reference::transport_cache;
use translucent::render::edit::SceneEdit;
use translucent::render::plan::Change;
use translucent::render::records::SplatRecord;
use translucent::render::renderer::Renderer;
use translucent::render::transport_tables::level_cells;
use translucent::scene::build::{KernelDropped, Overrides, PreparedScene, ResolvedMaterial};
use translucent::scene::needs::KernelState;
use translucent::scene::{Scene, Transform};

/// A sphere of `radius` mm (1 unit = 1 mm) of `material` (TOML fields) with `model`, under
/// one directional light.
fn sphere(radius: f64, divisions: u32, material: &str, model: &str) -> PreparedScene {
    let text = format!(
        r#"
[camera]
eye = [0.0, {eye_y}, {eye_z}]
target = [0.0, 0.0, 0.0]
resolution = [32, 32]

[[object]]
shape = {{ type = "sphere", radius = {radius}, divisions = {divisions} }}
material = {{ type = "translucent", {material}, mm_per_unit = 1.0, model = "{model}" }}
casts_shadow = false

[[light]]
type = "directional"
direction = [0.8, 0.5, 0.3]
irradiance = [1.0, 1.0, 1.0]

[sampling]
count = 1500
"#,
        eye_y = 1.2 * radius,
        eye_z = 4.5 * radius,
    );
    PreparedScene::new(&Scene::parse(&text, "test.toml", None).unwrap(), &Overrides::default()).unwrap()
}

fn quiet(_: usize, _: usize) {}

/// Kernel settings of exactly `walks` walks per channel, whatever the mesh's size (the tests'
/// figures were set for these counts, not for `KernelSettings::walks_for`'s small-mesh rule).
fn fixed(patches: usize, walks: u64, seed: u64) -> KernelSettings {
    KernelSettings { patches, walks, seed, more_on_small_meshes: false }
}

/// The half-space's albedo for light entering as the kernel's walks do at eta 1 (`sin^2` of
/// the entry uniform: `mu^2` uniform), `2 int R(mu) mu dmu`, by four-point Gauss-Legendre in
/// `mu^2` over `rte::half_space_reflectance` at each node.
fn diffuse_half_space(medium: &Medium) -> f64 {
    let (x, w) = ([0.339_981_043_584_856, 0.861_136_311_594_053], [0.652_145_154_862_546, 0.347_854_845_137_454]);
    let mut sum = 0.0;
    for (&x, &w) in x.iter().zip(&w) {
        for u in [0.5 - 0.5 * x, 0.5 + 0.5 * x] {
            let r = half_space_reflectance(medium, f64::sqrt(u), &Budget::photons(200_000), 5, &|_| {}).unwrap();
            sum += 0.5 * w * r.mean;
        }
    }
    sum
}

#[test]
fn a_kernel_on_a_sphere_far_wider_than_its_diffusion_length_reflects_what_the_half_space_does() {
    // sigma_s' 10/mm, sigma_a 0.5 to 2/mm (diffusion lengths 0.13 to 0.25 mm) at eta 1 in a
    // 100 mm sphere: locally a half-space, so the flux out per unit flux in (a column's sum of
    // W0, the entries' mean) is the half-space's albedo under the same entries (Chandrasekhar's
    // plane albedo, `rte::half_space_reflectance`, checked against the H-function in
    // tests/rte.rs, averaged over them) within 1%.
    let scene =
        sphere(100.0, 24, "sigma_a = [1.0, 2.0, 0.5], sigma_s_prime = [10.0, 10.0, 10.0], eta = 1.0", "transport");
    let o = &scene.objects[0];
    let settings = fixed(16, 16 * 8000, 3);
    let kernel = object_kernel(o, &settings, &quiet).unwrap();
    let ResolvedMaterial::Translucent { dipoles, .. } = &o.material else { unreachable!() };
    let k = kernel.patches.len();
    for (c, dipole) in dipoles.iter().enumerate() {
        let medium = Medium::reduced(dipole);
        let exact = diffuse_half_space(&medium);
        let columns: Vec<f64> = (0..k).map(|j| (0..k).map(|i| kernel.flux[c][i * k + j]).sum()).collect();
        let mean = columns.iter().sum::<f64>() / k as f64;
        let relative = (mean - exact) / exact;
        assert!(relative.abs() < 0.01, "channel {c}: kernel {mean:.4} against the half-space's {exact:.4}");
        // Energy: no patch sends out more than came in.
        assert!(columns.iter().all(|&s| s > 0.0 && s <= 1.0), "channel {c}: {columns:?}");
    }
}

#[test]
fn a_kernel_brightens_a_marble_sphere_the_dipole_leaves_too_dark_and_keeps_energy() {
    // The 2 cm marble sphere: the light the half-space loses deep below comes back out, so
    // each patch sends out more than the dipole's R_d,total, and never more than came in.
    let scene = sphere(10.0, 12, "preset = \"marble\"", "transport");
    let o = &scene.objects[0];
    let kernel = object_kernel(o, &fixed(24, 16 * 400, 1), &quiet).unwrap();
    let ResolvedMaterial::Translucent { dipoles, .. } = &o.material else { unreachable!() };
    let k = kernel.patches.len();
    for (c, dipole) in dipoles.iter().enumerate() {
        let total: f64 = kernel.flux[c].iter().sum::<f64>() / k as f64;
        let dipole = dipole.r_d_total();
        assert!(total > 1.05 * dipole && total <= 1.0, "channel {c}: kernel {total:.3}, dipole {dipole:.3}");
    }
}

/// The three channels walk on the same random numbers: on a sphere, where every patch is alike,
/// what each patch sends out differs between patches by noise alone, and that noise is alike in
/// red and green (correlated across the patches), so the kernel errs in brightness, not in hue.
#[test]
fn the_channels_share_their_walks_so_a_patchs_noise_is_alike_in_every_channel() {
    let scene = sphere(10.0, 12, "preset = \"marble\"", "transport");
    let kernel = object_kernel(&scene.objects[0], &fixed(24, 24 * 200, 7), &quiet).unwrap();
    let k = kernel.patches.len();
    let sent = |c: usize| (0..k).map(|j| (0..k).map(|i| kernel.flux[c][i * k + j]).sum::<f64>()).collect::<Vec<_>>();
    let (r, g) = (sent(0), sent(1));
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (mr, mg) = (mean(&r), mean(&g));
    let cov = |a: &[f64], ma: f64, b: &[f64], mb: f64| a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum::<f64>();
    let correlation = cov(&r, mr, &g, mg) / (cov(&r, mr, &r, mr) * cov(&g, mg, &g, mg)).sqrt();
    // 0.68 here; 0.32 when each channel walked on its own numbers.
    assert!(correlation > 0.5, "red and green per patch correlate {correlation:.3}");
}

/// The 2 cm marble sphere (12 divisions) and its kernel of 24 patches and 2,000 walks each,
/// walked once for the tests that read its rows.
fn marble_kernel_of_24_patches() -> &'static (PreparedScene, TransportKernel) {
    static KERNEL: std::sync::OnceLock<(PreparedScene, TransportKernel)> = std::sync::OnceLock::new();
    KERNEL.get_or_init(|| {
        let scene = sphere(10.0, 12, "preset = \"marble\"", "transport");
        let settings = fixed(24, 24 * 2000, 4);
        let kernel = object_kernel(&scene.objects[0], &settings, &quiet).unwrap();
        (scene, kernel)
    })
}

#[test]
fn tilting_the_entry_towards_a_nearby_patch_sends_it_more_light_and_the_entry_rows_end_at_their_reach() {
    // The 2 cm marble sphere: light entering patch J tilted towards a neighbour I runs towards
    // it under the surface, so Wt_IJ, summed over J's neighbours within the reach, is positive
    // in every channel; beyond each channel's reach the row is not walked.
    use translucent::optics::transport::entry_reach;
    let (scene, kernel) = marble_kernel_of_24_patches();
    let (k, p) = (kernel.patches.len(), &kernel.patches);
    let distance = |i: usize, j: usize| p.centre(i).distance(p.centre(j));
    let ResolvedMaterial::Translucent { dipoles, .. } = &scene.objects[0].material else { panic!("translucent") };
    for (c, dipole) in dipoles.iter().enumerate() {
        let reach = entry_reach(p.radius, dipole.diffusion_length());
        let (mut near, mut out_of_reach) = (0.0, 0usize);
        for i in 0..k {
            for j in (0..k).filter(|&j| j != i) {
                let w = kernel.sideways[c][i * k + j];
                if distance(i, j) <= reach {
                    near += w;
                } else if w != 0.0 || kernel.depth[c][i * k + j] != 0.0 {
                    out_of_reach += 1;
                }
            }
        }
        let direct: f64 = (0..k).map(|i| kernel.flux[c][i * k + i]).sum();
        assert!(near > 0.05 * direct, "channel {c}: tilt row near {near:.4}, W0's diagonal {direct:.4}");
        assert_eq!(out_of_reach, 0, "channel {c}: entry rows walked beyond the reach");
    }
}

#[test]
fn light_entering_a_patch_on_its_side_towards_a_far_patch_sends_it_more_and_a_uniform_entry_no_offset() {
    // The 2 cm marble sphere: the flux reaching a patch I falls with the distance it runs, so
    // light entering J on its side towards I sends I more than light entering on the far side:
    // Wx_IJ, summed over the pairs beyond the entry rows' reach, is positive in every channel
    // and, times a patch radius, a sizeable share of their W0. And where every vertex's cell
    // is lit alike, the offsets from each patch's entry centre cancel: X_J = 0 and the row adds
    // nothing to what W0 says.
    use translucent::mesh::patches::cell_centroids;
    use translucent::optics::transport::ENTRY_REACH;
    let (scene, kernel) = marble_kernel_of_24_patches();
    let (k, p) = (kernel.patches.len(), &kernel.patches);
    for c in 0..3 {
        let (mut shift, mut flux) = (0.0, 0.0);
        for i in 0..k {
            for j in (0..k).filter(|&j| p.centre(i).distance(p.centre(j)) > ENTRY_REACH * p.radius) {
                shift += kernel.shift[c][i * k + j] * p.radius;
                flux += kernel.flux[c][i * k + j];
            }
        }
        assert!(shift > 0.1 * flux, "channel {c}: Wx times a radius {shift:.4} against W0 {flux:.4} beyond the reach");
    }
    let mesh = &scene.objects[0].mesh;
    let centroids = cell_centroids(mesh);
    let uniform = (0..mesh.positions().len()).map(|v| {
        let n = mesh.vertex_normals()[v].as_dvec3();
        SampleFlux::from_splat(
            (p.of_vertex[v], centroids[v]),
            p.cells[v],
            [1.0; 3],
            (DVec3::ZERO, 0.0),
            n,
            kernel.mu_mean,
        )
    });
    let flux = kernel.patch_flux(uniform, &p.entry_centres(mesh));
    for j in 0..k {
        let offset = flux.offset[j][0].length() / (flux.phi[j][0] * p.radius);
        assert!(offset < 1e-9, "patch {j}: uniform light's offset {offset:.2e} of a radius");
    }
}

#[test]
fn in_skim_milk_the_entry_rows_reach_a_diffusion_length_farther_in_red_than_in_blue() {
    // Skim milk's red runs 18.4 mm, its blue 3.5 mm: on a 2 cm sphere of 24 patches (radius
    // about 4 mm) red's rows reach past three radii, blue's stop there.
    let scene = sphere(10.0, 12, "preset = \"skimmilk\"", "transport");
    let kernel = object_kernel(&scene.objects[0], &fixed(24, 24 * 200, 4), &quiet).unwrap();
    let k = kernel.patches.len();
    let pairs = |c: usize| (0..k * k).filter(|&at| kernel.depth[c][at] != 0.0).count();
    let (red, blue) = (pairs(0), pairs(2));
    assert!(red as f64 > 1.5 * blue as f64, "pairs with an entry row: red {red}, blue {blue}");
}

#[test]
fn the_kernel_is_reciprocal_flux_from_j_to_i_equals_flux_from_i_to_j_within_its_noise() {
    // The radiative transfer is reciprocal: under uniform irradiance, the flux that J sends out
    // through I equals what I sends through J, A_J W0_IJ = A_I W0_JI. The walks enter as
    // diffuse light refracts in and leave through the Fresnel boundary, the same angular weight
    // both ways up to Fresnel's transmittance, which the sphere's patches share.
    let scene = sphere(10.0, 12, "preset = \"marble\"", "transport");
    let kernel = object_kernel_walks(&scene.objects[0], &fixed(24, 24 * 4000, 5), &quiet).unwrap();
    let (k, area) = (kernel.patches.len(), &kernel.patches.area);
    for c in 0..3 {
        let w = &kernel.flux[c];
        // The pairs that exchange at least a twentieth of what a patch sends itself: farther, a
        // few hundred of the walks reach, and the ratio is noise.
        let floor = 0.05 * (0..k).map(|i| area[i] * w[i * k + i]).sum::<f64>() / k as f64;
        let mut logs = Vec::new();
        for i in 0..k {
            for j in (i + 1)..k {
                let (ij, ji) = (area[j] * w[i * k + j], area[i] * w[j * k + i]);
                if ij.min(ji) > floor {
                    logs.push((ij / ji).ln());
                }
            }
        }
        let mean = logs.iter().sum::<f64>() / logs.len() as f64;
        let within = logs.iter().filter(|l| l.abs() < 0.2).count() as f64 / logs.len() as f64;
        eprintln!("channel {c}: mean log ratio {mean:.4}, share within 20% {within:.3}, pairs {}", logs.len());
        assert!(mean.abs() < 0.05, "channel {c}: A_J W_IJ / A_I W_JI averages exp({mean:.4})");
        assert!(within > 0.9, "channel {c}: only {within:.3} of the pairs are reciprocal within 20%");
    }
}

#[test]
fn averaging_each_pair_with_its_reciprocal_brings_the_kernel_closer_to_one_of_twelve_times_the_walks() {
    // The walks entering J and those entering I estimate A_J W0_IJ = A_I W0_JI independently:
    // their mean should have about half the variance, an RMS error about 0.7 times either's.
    let scene = sphere(10.0, 12, "preset = \"marble\"", "transport");
    let at = |walks: u64, seed| fixed(24, 24 * walks, seed);
    let fine = object_kernel(&scene.objects[0], &at(12_000, 9), &quiet).unwrap();
    let raw = object_kernel_walks(&scene.objects[0], &at(1_000, 5), &quiet).unwrap();
    let averaged = raw.clone().reciprocal();
    let (k, area) = (fine.patches.len(), &fine.patches.area);
    let off_diagonal = |w: &[f64], f: &[f64]| {
        let pairs = (0..k * k).filter(|at| at / k != at % k);
        let (e2, f2) = pairs.fold((0.0, 0.0), |(e, s), at| (e + (w[at] - f[at]).powi(2), s + f[at] * f[at]));
        (e2 / f2).sqrt()
    };
    for c in 0..3 {
        let (raw_error, averaged_error) =
            (off_diagonal(&raw.flux[c], &fine.flux[c]), off_diagonal(&averaged.flux[c], &fine.flux[c]));
        eprintln!(
            "channel {c}: off-diagonal W0 from the fine kernel's, walks {raw_error:.4}, averaged {averaged_error:.4}"
        );
        assert!(averaged_error < 0.85 * raw_error, "channel {c}: averaged {averaged_error:.4}, walks {raw_error:.4}");
        let w = &averaged.flux[c];
        for (i, j) in (0..k).flat_map(|i| (0..k).map(move |j| (i, j))) {
            let (ij, ji) = (area[j] * w[i * k + j], area[i] * w[j * k + i]);
            assert!((ij - ji).abs() <= 1e-12 * ij.abs().max(ji.abs()), "channel {c}: pair {i}, {j} not reciprocal");
        }
        assert_eq!(
            (0..k).map(|i| w[i * k + i]).collect::<Vec<_>>(),
            (0..k).map(|i| raw.flux[c][i * k + i]).collect::<Vec<_>>(),
            "channel {c}: a patch's own entry has no partner and stays"
        );
    }
}

/// The splat's record per sample.
type Splat = Vec<SplatRecord>;

/// Object 0's exitance at every vertex after one full frame gathered at level of detail `level`
/// (0 off the level's vertices, which the frame leaves alone), and the splat's irradiance and
/// area per sample.
fn frame_at(prepared: PreparedScene, level: usize) -> (Vec<[f32; 3]>, Splat) {
    let count = prepared.objects[0].mesh.positions().len();
    common::with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, prepared).unwrap();
        let mut plan = renderer.plan(Change::Everything);
        plan.objects.iter_mut().for_each(|o| o.level = level);
        renderer.frame(&plan).unwrap();
        let at = renderer.exitance_at_level(0).unwrap();
        assert_eq!(at.level, level);
        let mut all = vec![[0.0f32; 3]; count];
        at.vertices.iter().zip(&at.values).for_each(|(&v, m)| all[v as usize] = *m);
        (all, renderer.splat_records().unwrap())
    })
}

/// Object 0's exitance after one full frame at level 0, and the splat.
fn frame(prepared: PreparedScene) -> (Vec<[f32; 3]>, Splat) {
    frame_at(prepared, 0)
}

/// The worst difference of the GPU's scaled exitance from the f64 twin, and the largest change
/// the kernel makes to the dipole, both as a share of the brightest vertex, for `scene` with
/// `kernel` attached to object 0, gathered at level of detail `level`.
fn against_twin(mut scene: PreparedScene, kernel: &TransportKernel, level: usize) -> (f64, f64) {
    let without = |mut o: translucent::scene::build::PreparedObject| {
        o.transport = None;
        o
    };
    let dipole_scene = PreparedScene { objects: scene.objects.iter().cloned().map(without).collect(), ..scene.clone() };
    scene.objects[0].transport = Some(std::sync::Arc::new(kernel.clone()));
    let (scaled, splat) = frame_at(scene.clone(), level);
    // Without a kernel the object takes the dipole: the same splat and gather, unscaled.
    let (dipole, _) = frame_at(dipole_scene, level);
    let o = &scene.objects[0];
    let placed = kernel.placed(&o.mesh);
    let points = o.samples.iter().zip(&splat).map(|(s, r)| {
        let e = [0, 1, 2].map(|c| f64::from(r.irradiance_area[c]));
        let (d, w) = r.key_entry();
        let d = DVec3::from(d.map(f64::from));
        let patch = kernel.sample_patch(&o.mesh, s.triangle, s.barycentric);
        let at = (patch, s.position.as_dvec3());
        SampleFlux::from_splat(at, s.area, e, (d, f64::from(w)), s.normal.as_dvec3(), kernel.mu_mean)
    });
    let phi = kernel.patch_flux(points, &placed.entry_centres(&o.mesh));
    let dipole64: Vec<[f64; 3]> = dipole.iter().map(|m| m.map(f64::from)).collect();
    let near = TransportKernel::vertex_neighbours(&placed, &o.mesh);
    let cells = level_cells(o, &o.levels[level].triangles);
    let twin = kernel.exitance((&phi, &placed), (&dipole64, &cells), &near);
    let brightest = twin.iter().flatten().fold(0.0f64, |a, &b| a.max(b));
    let (mut worst, mut changed) = (0.0f64, 0.0f64);
    for ((g, t), d) in scaled.iter().zip(&twin).zip(&dipole64) {
        for c in 0..3 {
            assert!(g[c].is_finite() && g[c] >= 0.0);
            worst = worst.max((f64::from(g[c]) - t[c]).abs() / brightest);
            changed = changed.max((t[c] - d[c]).abs() / brightest);
        }
    }
    (worst, changed)
}

#[test]
fn the_gpu_transport_pass_matches_its_f64_twin_at_each_level_and_after_a_rigid_move() {
    let scene = sphere(10.0, 24, "preset = \"marble\"", "transport");
    assert!(scene.objects[0].levels.len() > 1, "the test needs a coarser level of detail");
    let kernel = object_kernel(&scene.objects[0], &fixed(48, 48 * 300, 2), &quiet).unwrap();
    for level in [0, scene.objects[0].levels.len() - 1] {
        let (worst, changed) = against_twin(scene.clone(), &kernel, level);
        assert!(worst < 1e-4, "level {level}: GPU against its f64 twin, {worst:.2e} of the brightest vertex");
        assert!(changed > 0.05, "level {level}: the kernel must change the picture, {changed:.3}");
    }
    // Turned and moved: the same kernel, its patches following the vertices.
    let mut moved = scene.clone();
    moved.objects[0].transport = Some(std::sync::Arc::new(kernel.clone()));
    let rigid =
        Transform { rotate: Some([30.0, 60.0, 0.0]), translate: Some([3.0, -2.0, 1.0]), ..Transform::default() };
    moved.set_transform(0, rigid).unwrap();
    assert_eq!(moved.objects[0].transport.as_deref(), Some(&kernel), "a rigid move keeps the kernel");
    let (worst, changed) = against_twin(moved, &kernel, 0);
    assert!(worst < 1e-4 && changed > 0.05, "after the move: {worst:.2e}, {changed:.3}");
}

#[test]
fn in_ketchup_the_kernel_scales_red_and_leaves_green_and_blue_to_single_scattering_between_points() {
    let scene = sphere(10.0, 24, "preset = \"ketchup\"", "transport");
    assert_eq!(scene.objects[0].single_channels(), [false, true, true], "ketchup's reduced albedos");
    let settings = fixed(48, 48 * 300, 2);
    let kernel = object_kernel(&scene.objects[0], &settings, &quiet).unwrap();
    let mut with = scene.clone();
    with.objects[0].transport = Some(std::sync::Arc::new(kernel));
    // Without a kernel attached: the dipole in red, single scattering between points in green
    // and blue, as model = "auto" draws them.
    let (unscaled, _) = frame(scene);
    let (scaled, _) = frame(with);
    assert!(scaled.iter().zip(&unscaled).all(|(s, u)| s[1] == u[1] && s[2] == u[2]), "green and blue were scaled");
    let brightest = unscaled.iter().map(|m| m[0]).fold(0.0f32, f32::max);
    let changed = scaled.iter().zip(&unscaled).map(|(s, u)| (s[0] - u[0]).abs()).fold(0.0f32, f32::max);
    assert!(changed > 0.05 * brightest, "red must be scaled: {changed} of {brightest}");
}

#[test]
fn a_scale_or_a_material_edit_drops_the_kernel_with_its_reason_and_the_dipole_takes_over() {
    let mut scene = sphere(10.0, 12, "preset = \"marble\"", "transport");
    let kernel = object_kernel(&scene.objects[0], &fixed(24, 16 * 100, 2), &quiet).unwrap();
    scene.objects[0].transport = Some(std::sync::Arc::new(kernel));
    let mut scaled = scene.clone();
    scaled.set_transform(0, Transform { scale: Some(1.5), ..Transform::default() }).unwrap();
    assert!(scaled.objects[0].transport.is_none());
    assert_eq!(scaled.objects[0].kernel_dropped, Some(KernelDropped::Scaled));
    let dipole_scene = PreparedScene {
        objects: scene
            .objects
            .iter()
            .cloned()
            .map(|mut o| {
                o.transport = None;
                o
            })
            .collect(),
        ..scene.clone()
    };
    let (dipole, _) = frame(dipole_scene);
    let ResolvedMaterial::Translucent { material, .. } = scene.objects[0].material.clone() else { unreachable!() };
    common::with_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, scene).unwrap();
        let mut plan = renderer.plan(Change::Everything);
        plan.objects.iter_mut().for_each(|o| o.level = 0);
        assert!(matches!(plan.objects[0].transport, Some(KernelState::Scales { .. })), "{plan}");
        renderer.frame(&plan).unwrap();
        assert_ne!(renderer.exitance(0).unwrap(), dipole);
        renderer.edit(SceneEdit::Material { object: 0, material }).unwrap();
        let mut plan = renderer.plan(Change::Material(0));
        plan.objects.iter_mut().for_each(|o| o.level = 0);
        let text = plan.to_string();
        assert_eq!(plan.objects[0].transport, Some(KernelState::Dropped { why: KernelDropped::MaterialEdited }));
        assert!(text.contains("transport kernel dropped: its material was edited"), "{text}");
        renderer.frame(&plan).unwrap();
        // The same coefficients, the kernel gone: the dipole's exitance exactly.
        assert_eq!(renderer.exitance(0).unwrap(), dipole);
    });
}

#[test]
fn a_damaged_or_foreign_kernel_cache_file_is_walked_anew_never_used() {
    let dir = common::temp_dir("transport-cache");
    let scene = sphere(10.0, 8, "preset = \"marble\"", "transport");
    let o = &scene.objects[0];
    let settings = fixed(8, 7 * 50, 4);
    let (first, cached) = transport_cache::cached(o, &settings, &dir, &quiet).unwrap();
    assert!(!cached);
    let (again, cached) = transport_cache::cached(o, &settings, &dir, &quiet).unwrap();
    assert!(cached);
    assert_eq!(first, again);
    let path = dir.join(format!("kernel-{}.json", transport_cache::content_key(o, &settings)));
    // One value edited: the checksum no longer matches, so the file is walked anew.
    let text = std::fs::read_to_string(&path).unwrap();
    let walks = format!("\"walks\":{}", first.walks);
    let edited = text.replacen(&walks, &format!("\"walks\":{}", first.walks + 1), 1);
    assert!(edited != text, "the file holds {walks}");
    std::fs::write(&path, edited).unwrap();
    let (walked, cached) = transport_cache::cached(o, &settings, &dir, &quiet).unwrap();
    assert!(!cached, "an edited file must not be used");
    assert_eq!(walked, first);
    // Another setting is another key: never this file.
    let other = KernelSettings { walks: 7 * 60, ..settings };
    assert_ne!(transport_cache::content_key(o, &other), transport_cache::content_key(o, &settings));
    // A folder that cannot be written in fails at once, naming it.
    let file = dir.join("a-file");
    std::fs::write(&file, "x").unwrap();
    let err = transport_cache::cached(o, &other, &file, &quiet).unwrap_err();
    assert!(err.to_string().contains("a-file"), "{err}");
}

/// Per channel, the relative RMS of `drawn` against the RTE `reference` (with its standard
/// errors `se`) over the vertices the reference holds that face the light (`cos` over 0.3), and
/// the reference's own share of that (the RMS of its relative standard errors).
fn against_light(drawn: &[[f32; 3]], (reference, se): &(Vec<[f64; 3]>, Vec<[f64; 3]>), cos: &[f64]) -> [[f64; 2]; 3] {
    [0, 1, 2].map(|c| {
        let lit: Vec<usize> = (0..drawn.len()).filter(|&v| reference[v][c] > 0.0 && cos[v] > 0.3).collect();
        let n = lit.len().max(1) as f64;
        let rel = |v: usize| f64::from(drawn[v][c]) / reference[v][c] - 1.0;
        let rms = (lit.iter().map(|&v| rel(v).powi(2)).sum::<f64>() / n).sqrt();
        let noise = (lit.iter().map(|&v| (se[v][c] / reference[v][c]).powi(2)).sum::<f64>() / n).sqrt();
        [rms, noise]
    })
}

/// Issue 49: a kernel walked once, without the lights, and read from its cache after the light
/// moves, draws (on the GPU, every vertex) within its model error of the RTE walked for each
/// light (60 receivers spread over the sphere, 2,500 walks each: about 4% noise a vertex; those
/// facing the light compared), where the dipole is 20% off.
#[test]
fn a_cached_kernel_follows_a_moving_light_as_the_rte_does_where_the_dipole_does_not() {
    use translucent::reference::rte_mesh::{self, MeshOptions, Walk};
    use translucent::scene::lights;
    // A 6 mm marble sphere, under two diffusion lengths across: the dipole's half-space is far
    // from it, and the RTE's walks are short.
    let scene = sphere(3.0, 24, "preset = \"marble\"", "transport");
    let dir = std::env::temp_dir().join(format!("translucent-kernel-light-{}", std::process::id()));
    let settings = fixed(48, 48 * 400, 6);
    let (kernel, cached) = transport_cache::cached(&scene.objects[0], &settings, &dir, &quiet).unwrap();
    assert!(!cached, "a fresh folder holds no kernel");
    let count = scene.objects[0].mesh.positions().len();
    common::with_gpu(|gpu| {
        let renderer = |kernel: Option<TransportKernel>| {
            let mut s = scene.clone();
            s.objects[0].transport = kernel.map(std::sync::Arc::new);
            Renderer::new(gpu, s).unwrap()
        };
        let mut rows = [renderer(Some(kernel)), renderer(None)];
        for step in 0..2 {
            if step > 0 {
                // The light moves; the kernel, which knows no light, is read from the cache.
                let (again, cached) = transport_cache::cached(&scene.objects[0], &settings, &dir, &quiet).unwrap();
                assert!(cached && Some(&again) == rows[0].scene().objects[0].transport.as_deref());
                for r in rows.iter_mut() {
                    let light = lights::orbit(&r.scene().scene.file.lights[0], glam::Vec3::ZERO, 100.0).unwrap();
                    r.edit(SceneEdit::Light { index: 0, light }).unwrap();
                }
            }
            let change = if step == 0 { Change::Everything } else { Change::Light(0) };
            let drawn: Vec<Vec<[f32; 3]>> = rows
                .iter_mut()
                .map(|r| {
                    let mut plan = r.plan(change);
                    plan.objects.iter_mut().for_each(|o| o.level = 0);
                    r.frame(&plan).unwrap();
                    r.exitance(0).unwrap()
                })
                .collect();
            let lit = rows[0].scene().clone();
            let options = MeshOptions {
                budget: Budget::photons(2500),
                seed: 11 + step,
                walk: Walk::Adjoint { receivers: Some(60) },
            };
            let reference = rte_mesh::exitance(&lit, &options, &|_| {}).unwrap().remove(0).unwrap().per_vertex(count);
            let cos = translucent::study::physics::light_cosines(&lit).remove(0);
            let [kernel, dipole] = [0, 1].map(|i| against_light(&drawn[i], &reference, &cos));
            println!("light {step}: [total, reference noise] per channel: kernel {kernel:.4?}, dipole {dipole:.4?}");
            for c in 0..3 {
                // The kernel's own error (7.66 to 8.59% on the 2 cm sphere, docs/STUDY.md) with
                // the reference's noise taken out, and far under the dipole's.
                let model = (kernel[c][0].powi(2) - kernel[c][1].powi(2)).max(0.0).sqrt();
                assert!(model < 0.10, "light {step}, channel {c}: the kernel {model:.4} off the RTE");
                assert!(
                    kernel[c][0] < 0.5 * dipole[c][0],
                    "light {step}, channel {c}: {kernel:.4?} against {dipole:.4?}"
                );
            }
        }
    });
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_mesh_under_thirty_thousand_vertices_takes_up_to_five_times_the_walks_and_the_bunny_the_setting() {
    let d = KernelSettings::default();
    assert_eq!(d.walks_for(37_706), d.walks);
    assert_eq!(d.walks_for(1_106), 5 * d.walks);
    let between = d.walks_for(15_000);
    assert!(between > d.walks && between < 2 * d.walks, "{between}");
    assert_eq!(KernelSettings { more_on_small_meshes: false, ..d }.walks_for(1_106), d.walks);
}

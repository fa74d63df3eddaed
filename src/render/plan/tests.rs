use super::*;
use crate::scene::TransportMode;
use crate::scene::needs::{ChannelFacts, LevelFacts, ObjectFacts};

fn object(radius: f32, spacing: f64, profile: f64) -> ObjectFacts {
    let channel = ChannelFacts { diffusion_length: profile, z_v: profile, profile_radius: profile, r_d_total: 0.5 };
    ObjectFacts {
        name: "sphere".into(),
        single: [None; 3],
        transport: None,
        center: [0.0, 0.0, 0.0],
        radius,
        sample_spacing: spacing,
        vertex_spacing: spacing / 4.0,
        channels: Some([channel; 3]),
        levels: vec![LevelFacts {
            triangles: 1000,
            vertices: 500,
            mean_edge: spacing / 4.0,
            error: 0.0,
            locked: false,
        }],
        density: None,
        model: None,
    }
}

/// Three levels: 0.5, 5 and 20 pixels per edge at the origin in `view()` (0.1 units a
/// pixel), 0, 0.2 and 0.1 pixels from the whole mesh.
fn levels() -> Vec<LevelFacts> {
    [(1000, 0.05, 0.0), (250, 0.5, 0.02), (60, 2.0, 0.01)]
        .map(|(triangles, mean_edge, error)| LevelFacts {
            triangles,
            vertices: triangles / 2,
            mean_edge,
            error,
            locked: false,
        })
        .to_vec()
}

fn needs(shadow_layers: u32, translucent_objects: usize) -> SceneNeeds {
    SceneNeeds {
        shadow_layers,
        translucent_objects,
        shadowed_lights: if shadow_layers > 0 { vec![0] } else { vec![] },
        environment: (shadow_layers > 1).then_some(1),
        pixel_gather: false,
        host_target: false,
        transport: TransportMode::Auto,
        splat_visibility: crate::scene::SplatVisibility::Hybrid,
        gather: crate::scene::GatherMode::Vertex,
        receivers: crate::scene::ReceiverPolicy::VisibleFirst,
        objects: (0..translucent_objects).map(|_| object(1.0, 0.1, 0.3)).collect(),
        shadow_texel: 0.01,
        caster_center: [0.0; 3],
    }
}

/// Looking down -z at the origin from z = 5, 90 degrees vertically, 100 pixels high.
fn view() -> View {
    let projection = glam::camera::rh::proj::vulkan::perspective(std::f32::consts::FRAC_PI_2, 1.0, 0.1, 100.0);
    let view = glam::camera::rh::view::look_at_mat4(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y);
    View { view_proj: projection * view, projection, eye: Vec3::new(0.0, 0.0, 5.0), height: 100 }
}

/// The plan after `change` for a history where each object `i` is stale when `stale[i]` and was
/// last gathered at level `gathered[i]`.
fn plan(needs: &SceneNeeds, view: &View, stale: &[bool], gathered: &[usize], change: Change) -> Plan {
    Planner::with_history(stale, gathered).plan_for(needs, view, change)
}

/// The plan after `change` when every object is current at its whole mesh.
fn run(needs: &SceneNeeds, change: Change) -> Plan {
    plan(needs, &view(), &vec![false; needs.objects.len()], &vec![0; needs.objects.len()], change)
}

#[test]
fn the_coarsest_level_within_the_edge_and_error_limits_is_drawn() {
    let mut n = needs(1, 1);
    n.objects[0].levels = levels();
    let p = run(&n, Change::Camera);
    // Level 2's 20-pixel edges are past LOD_EDGE_PIXELS; level 1's 5 are within.
    assert_eq!(p.objects[0].level, 1, "{p}");
    assert!(matches!(p.objects[0].level_why, LevelReason::WithinLimits { triangles: 250, .. }), "{p}");
    assert!(p.objects[0].level_why.to_string().contains("250 of 1000 triangles"), "{p}");
    // Half a pixel from the whole mesh is the other limit: level 1 at 0.6 pixels is out.
    n.objects[0].levels[1].error = 0.06;
    assert_eq!(run(&n, Change::Camera).objects[0].level, 0);
}

#[test]
fn a_finer_level_coming_into_use_is_gathered_again_without_a_splat() {
    let mut n = needs(1, 1);
    n.objects[0].levels = levels();
    // The last gather ran at level 2; this frame draws level 1, whose extra vertices lack it.
    let p = plan(&n, &view(), &[false], &[2], Change::Camera);
    assert!(p.runs(Pass::Gather) && p.objects[0].gather, "{p}");
    assert!(!p.runs(Pass::Splat), "the samples' irradiance is current: {p}");
    // At the level last gathered, or a coarser one, nothing is redone.
    let p = plan(&n, &view(), &[false], &[1], Change::Camera);
    assert!(!p.runs(Pass::Gather), "{p}");
}

#[test]
fn levels_baked_from_sky_light_are_not_drawn_on_a_frame_that_recomputes_it() {
    // Light 1 is the environment (`needs` with 3 shadow layers).
    let mut n = needs(3, 1);
    n.objects[0].levels = levels();
    n.objects[0].levels.iter_mut().skip(1).for_each(|l| l.locked = true);
    // Locked levels are judged by their error alone: level 2's long edges do not count.
    assert_eq!(run(&n, Change::Camera).objects[0].level, 2);
    let p = run(&n, Change::Light(1));
    assert!(p.runs(Pass::VertexLight));
    assert_eq!(p.objects[0].level, 0, "{p}");
    assert_eq!(p.objects[0].level_why, LevelReason::SkyLightRecomputed, "{p}");
    // The key light moving leaves the sky light, and the baked levels, as they are.
    assert_eq!(run(&n, Change::Light(0)).objects[0].level, 2);
}

#[test]
fn out_of_view_an_object_takes_its_coarsest_level() {
    let mut n = needs(1, 1);
    n.objects[0].levels = levels();
    n.objects[0].center = [0.0, 0.0, 50.0];
    let p = run(&n, Change::Camera);
    assert!(!p.objects[0].in_view);
    assert_eq!(p.objects[0].level, 2, "{p}");
}

#[test]
fn shadow_texels_smaller_than_a_pixel_are_looked_up_with_one_tap() {
    // 0.01 units a texel against 0.1 a pixel at the casters' centre.
    let mut n = needs(1, 1);
    assert!(run(&n, Change::Camera).one_tap_shadows);
    n.shadow_texel = 0.5;
    let p = run(&n, Change::Camera);
    assert!(!p.one_tap_shadows && p.to_string().contains("four-tap tent"), "{p}");
    let filter = p.shadow_filter.expect("a shadow filter with shadows");
    assert!(!filter.one_tap && (filter.texel_pixels - 5.0).abs() < 1e-3, "{filter:?}");
}

#[test]
fn a_camera_move_only_shades() {
    let p = run(&needs(3, 1), Change::Camera);
    assert!(p.runs(Pass::Shade) && p.runs(Pass::Tonemap));
    assert!(!p.runs(Pass::Shadow) && !p.runs(Pass::Splat) && !p.runs(Pass::Gather));
    assert!(!p.runs(Pass::VertexLight));
}

#[test]
fn scenes_without_translucency_or_shadows_skip_those_passes() {
    let p = run(&needs(0, 0), Change::Everything);
    assert_eq!(p.passes.iter().map(|(p, _)| *p).collect::<Vec<_>>(), [Pass::Shade, Pass::Tonemap]);
    assert_eq!(p.skipped.len(), 4);
    let p = run(&needs(2, 1), Change::Everything);
    assert_eq!(p.passes.len(), 6);
}

#[test]
fn the_pixel_gather_follows_the_camera() {
    let mut n = needs(3, 1);
    n.pixel_gather = true;
    let p = run(&n, Change::Camera);
    let order: Vec<Pass> = p.passes.iter().map(|(p, _)| *p).collect();
    assert_eq!(order, [Pass::Shade, Pass::Gather, Pass::Tonemap]);
    // Every channel local: the pixel gather still runs, to finish the HDR alpha.
    n.objects[0] = object(1.0, 0.1, 0.01);
    let p = run(&n, Change::Camera);
    assert!(p.runs(Pass::Gather) && !p.objects[0].gather && !p.runs(Pass::Splat), "{p}");
}

#[test]
fn one_moved_light_redraws_only_its_shadows() {
    let p = run(&needs(3, 1), Change::Light(0));
    assert!(p.runs(Pass::Shadow) && p.runs(Pass::Splat) && p.runs(Pass::Gather));
    assert!(!p.runs(Pass::VertexLight), "the environment did not move");
    assert_eq!(p.shadow_light, Some(0));
    let p = run(&needs(3, 1), Change::Light(5));
    assert!(!p.runs(Pass::Shadow) && p.runs(Pass::Splat));
}

#[test]
fn a_profile_narrower_than_the_finest_detail_goes_local_and_skips_splat_and_gather() {
    let mut n = needs(1, 1);
    n.objects[0] = object(1.0, 0.1, 0.01);
    let p = run(&n, Change::Everything);
    assert_eq!(p.objects[0].local_mask(), 0b111);
    assert!(!p.runs(Pass::Splat) && !p.runs(Pass::Gather), "{p}");
    // The same object whose profile is wider than the samples' spacing is gathered.
    n.objects[0] = object(1.0, 0.1, 0.3);
    assert_eq!(run(&n, Change::Everything).objects[0].local_mask(), 0);
    // Forced either way by render.transport.
    n.transport = TransportMode::Local;
    assert_eq!(run(&n, Change::Everything).objects[0].local_mask(), 0b111);
    n.transport = TransportMode::Gather;
    n.objects[0] = object(1.0, 0.1, 0.01);
    assert_eq!(run(&n, Change::Everything).objects[0].local_mask(), 0);
}

#[test]
fn a_profile_wider_than_the_object_is_gathered_and_said_so() {
    let mut n = needs(1, 1);
    n.objects[0] = object(1.0, 5.0, 2.0);
    let p = run(&n, Change::Everything);
    assert_eq!(p.objects[0].local_mask(), 0);
    assert!(matches!(p.objects[0].channels[0].why, ChannelReason::WiderThanObject { .. }), "{p}");
    assert!(p.objects[0].channels[0].why.to_string().contains("wider than the object"), "{p}");
}

#[test]
fn an_object_out_of_view_waits_stale_until_it_is_seen() {
    let mut n = needs(1, 1);
    n.objects[0].center = [0.0, 0.0, 10.0]; // behind the eye
    let p = run(&n, Change::Light(0));
    assert!(!p.objects[0].in_view && !p.runs(Pass::Splat) && !p.runs(Pass::Gather));
    assert!(p.objects[0].stale_after);
    // Back in view with nothing else changed: it is gathered then.
    n.objects[0].center = [0.0, 0.0, 0.0];
    let p = plan(&n, &view(), &[true], &[usize::MAX], Change::Camera);
    assert!(p.objects[0].in_view && p.runs(Pass::Splat) && p.runs(Pass::Gather));
    assert!(!p.objects[0].stale_after);
}

#[test]
fn a_material_change_reruns_only_that_objects_splat_and_gather() {
    let mut n = needs(1, 2);
    n.objects[1].center = [0.5, 0.0, 0.0];
    let p = run(&n, Change::Material(1));
    assert!(!p.runs(Pass::Shadow) && p.runs(Pass::Splat) && p.runs(Pass::Gather));
    assert!(!p.objects[0].splat && p.objects[1].splat && p.objects[1].gather);
    let p = run(&n, Change::Geometry(1));
    assert!(p.runs(Pass::Shadow) && p.objects[0].gather && p.objects[1].gather);
}

#[test]
fn the_view_sees_spheres_in_its_frustum_and_measures_pixels() {
    let v = view();
    assert!(v.sees(Vec3::ZERO, 0.1) && !v.sees(Vec3::new(0.0, 0.0, 6.0), 0.5));
    assert!(!v.sees(Vec3::new(20.0, 0.0, 0.0), 1.0) && v.sees(Vec3::new(5.0, 0.0, 0.0), 1.0));
    // 90 degrees over 100 pixels: 2 d tan(45) / 100 per pixel.
    assert!((v.pixel_footprint(5.0) - 0.1).abs() < 1e-6);
}

#[test]
fn changes_fold_into_what_covers_both() {
    use Change::*;
    assert_eq!(Camera.and(Material(2)), Material(2));
    assert_eq!(Light(0).and(Material(2)), Light(0));
    assert_eq!(Geometry(1).and(Camera), Geometry(1));
    assert_eq!(Geometry(1).and(Light(0)), Everything);
    assert_eq!(Light(0).and(Light(1)), Lights);
}

#[test]
fn the_planner_keeps_what_recorded_frames_leave() {
    let mut n = needs(3, 1);
    n.objects[0].levels = levels();
    let mut planner = Planner::new(1, Change::Everything);
    assert_eq!(planner.pending(), Some(Change::Everything));
    let first = planner.plan(&n, &view());
    assert!(first.runs(Pass::VertexLight) && first.objects[0].gather, "{first}");
    planner.recorded(&first, true);
    assert_eq!(planner.pending(), None);
    assert_eq!(planner.baked_levels(), BakedLevels::Withdrawn, "the frame recomputed the sky light");
    planner.levels_baked();
    assert_eq!(planner.baked_levels(), BakedLevels::Current);
    // Gathered at level 1 (`levels()` in `view()`): the whole mesh's exitance is not current.
    assert_eq!(first.objects[0].level, 1);
    assert!(planner.gathered_coarser(0));
    assert!(!planner.plan(&n, &view()).runs(Pass::Gather), "nothing changed, nothing gathered");
    // A material change folded into a light's loses the object's name, not its staleness.
    planner.mark(Change::Material(0));
    planner.mark(Change::Light(0));
    assert_eq!(planner.pending(), Some(Change::Light(0)));
    let p = planner.plan(&n, &view());
    planner.recorded(&p, false);
    assert!(!planner.gathered_coarser(0), "a gather reaching every vertex");
    // The preview changes nothing: a camera frame after it is the same.
    let preview = planner.plan_for(&n, &view(), Change::Geometry(0));
    assert!(preview.runs(Pass::Shadow));
    assert_eq!(planner.pending(), None);
    assert!(!planner.plan(&n, &view()).runs(Pass::Splat));
}

#[test]
fn every_pass_runs_or_is_skipped_once_with_its_reason() {
    let mut n = needs(3, 2);
    n.objects[1].center = [0.0, 0.0, 50.0];
    for pixel_gather in [false, true] {
        n.pixel_gather = pixel_gather;
        for change in Change::all(2, 2) {
            let p = run(&n, change);
            let mut all: Vec<Pass> =
                p.passes.iter().map(|(p, _)| *p).chain(p.skipped.iter().map(|(p, _)| *p)).collect();
            all.sort_by_key(|p| p.name());
            assert_eq!(all.len(), 6, "{p}");
            all.dedup();
            assert_eq!(all.len(), 6, "{p}");
            let texts = p.passes.iter().map(|(_, w)| w.to_string()).chain(p.skipped.iter().map(|(_, w)| w.to_string()));
            assert!(texts.into_iter().all(|t| !t.is_empty()), "{p}");
            // Each object's splat and gather are what its reason says.
            for o in &p.objects {
                assert_eq!((o.splat, o.gather), o.why.splat_and_gather(), "{p}");
            }
            let json = p.to_json();
            assert!(
                json["passes"].as_array().unwrap().iter().all(|v| v["why"].as_str().is_some_and(|s| !s.is_empty()))
            );
            assert!(json["objects"][0]["why"].is_string() && json["objects"][0]["level_why"].is_string());
            assert!(json["objects"][0]["channels"][0]["why"].is_string() && json["shadow_filter_why"].is_string());
            // The splat's visibility is named exactly when a splat runs.
            assert_eq!(json["splat_visibility"].is_string(), p.runs(Pass::Splat), "{p}");
        }
    }
}

#[test]
fn withdrawn_baked_levels_leave_the_needs_one_level() {
    let mut scene = crate::scene::build::PreparedScene::new(
        &crate::scene::Scene::builtin(),
        &crate::scene::build::Overrides { samples: Some(16), ..Default::default() },
    )
    .unwrap();
    let object = scene.objects.iter().position(|o| o.levels.len() > 1).expect("an object with levels");
    let count = scene.objects[object].levels.len();
    assert_eq!(needs_of(&scene, BakedLevels::Withdrawn).objects[object].levels.len(), count, "none baked");
    scene.objects[object].levels[1].locked = true;
    assert_eq!(needs_of(&scene, BakedLevels::Current).objects[object].levels.len(), count);
    assert_eq!(needs_of(&scene, BakedLevels::Withdrawn).objects[object].levels.len(), 1);
    assert!(super::needs(&scene, true, BakedLevels::Current).host_target);
}

fn needs_of(scene: &crate::scene::build::PreparedScene, baked: BakedLevels) -> SceneNeeds {
    super::needs(scene, false, baked)
}

/// A hierarchically gathered scene of one translucent object with three levels, seen from
/// `view()`, under `policy`.
fn hierarchical(policy: crate::scene::ReceiverPolicy) -> SceneNeeds {
    let mut needs = needs(0, 1);
    needs.gather = crate::scene::GatherMode::Hierarchical;
    needs.receivers = policy;
    needs.objects[0].levels = levels();
    needs
}

/// Plan and record one frame after `change`.
fn step(planner: &mut Planner, needs: &SceneNeeds, view: &View, change: Change) -> ObjectPlan {
    planner.mark(change);
    let p = planner.plan(needs, view);
    planner.recorded(&p, true);
    p.objects[0].clone()
}

#[test]
fn after_a_change_the_unseen_receivers_are_swept_over_the_next_frames_then_nothing_runs() {
    let needs = hierarchical(crate::scene::ReceiverPolicy::VisibleFirst);
    let mut planner = Planner::new(1, Change::Everything);
    let first = step(&mut planner, &needs, &view(), Change::Everything);
    assert_eq!(first.receivers, ReceiverScope::VisibleFirst { generation: 1, fresh: true, sweep: None });
    let lit = step(&mut planner, &needs, &view(), Change::Lights);
    assert_eq!(lit.receivers, ReceiverScope::VisibleFirst { generation: 2, fresh: true, sweep: None });
    for chunk in 0..SWEEP_FRAMES {
        let o = step(&mut planner, &needs, &view(), Change::Camera);
        assert_eq!(o.why, ObjectReason::Sweeping { chunk, of: SWEEP_FRAMES });
        assert!(o.gather && !o.splat);
        let sweep = Some(Sweep { chunk, of: SWEEP_FRAMES });
        assert_eq!(o.receivers, ReceiverScope::VisibleFirst { generation: 2, fresh: false, sweep });
        assert_eq!(planner.sweep_pending(0), (chunk + 1 < SWEEP_FRAMES).then_some(2));
    }
    let settled = step(&mut planner, &needs, &view(), Change::Camera);
    assert_eq!(settled.why, ObjectReason::Unchanged);
    assert!(!settled.gather);
}

#[test]
fn a_sweep_starts_again_at_a_new_level_and_a_change_makes_a_new_generation() {
    let needs = hierarchical(crate::scene::ReceiverPolicy::VisibleFirst);
    let mut planner = Planner::new(1, Change::Everything);
    step(&mut planner, &needs, &view(), Change::Everything);
    step(&mut planner, &needs, &view(), Change::Camera);
    step(&mut planner, &needs, &view(), Change::Camera);
    // Twice as far: a coarser level, whose receivers the sweep starts over.
    let far = View { eye: Vec3::new(0.0, 0.0, 10.0), ..view() };
    let far = View {
        view_proj: far.projection * glam::camera::rh::view::look_at_mat4(far.eye, Vec3::ZERO, Vec3::Y),
        ..far
    };
    let o = step(&mut planner, &needs, &far, Change::Camera);
    assert!(o.level > 0);
    assert_eq!(o.why, ObjectReason::Sweeping { chunk: 0, of: SWEEP_FRAMES });
    // A light moving mid-sweep: a fresh gather under the next generation.
    let lit = step(&mut planner, &needs, &far, Change::Light(0));
    assert_eq!(lit.receivers, ReceiverScope::VisibleFirst { generation: 2, fresh: true, sweep: None });
}

#[test]
fn every_receiver_is_gathered_where_the_scene_asks_or_another_gather_or_between_points_needs_it() {
    let mut planner = Planner::new(1, Change::Everything);
    let asked = hierarchical(crate::scene::ReceiverPolicy::Every);
    let every = step(&mut planner, &asked, &view(), Change::Everything);
    assert_eq!(every.receivers, ReceiverScope::Every { why: EveryReason::Asked });
    assert_eq!(step(&mut planner, &asked, &view(), Change::Camera).why, ObjectReason::Unchanged);
    let flat = step(&mut Planner::new(1, Change::Everything), &needs(0, 1), &view(), Change::Everything);
    assert_eq!(flat.receivers, ReceiverScope::Every { why: EveryReason::GatherMode });
    let mut single = hierarchical(crate::scene::ReceiverPolicy::VisibleFirst);
    single.objects[0].single = [Some(0.1), None, None];
    let o = step(&mut Planner::new(1, Change::Everything), &single, &view(), Change::Everything);
    assert_eq!(o.receivers, ReceiverScope::Every { why: EveryReason::AfterGather });
    // A transport kernel's pass keeps the dipole values it needs: visible first still.
    let mut kernel = hierarchical(crate::scene::ReceiverPolicy::VisibleFirst);
    kernel.objects[0].transport = Some(crate::scene::needs::KernelState::Scales { patches: 48, walks: 4800 });
    let o = step(&mut Planner::new(1, Change::Everything), &kernel, &view(), Change::Everything);
    assert!(matches!(o.receivers, ReceiverScope::VisibleFirst { fresh: true, .. }), "{:?}", o.receivers);
}

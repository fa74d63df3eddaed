//! The shading and shadow passes cull the faces no ray from the eye or the light reaches
//! (`shade::hidden_faces`): the inner side of a surface that encloses a volume. The claims: the
//! image is the one every face drawn gives, and the faces culled are the hidden ones, only where
//! the near plane cuts nothing.

mod common;

use common::*;
use glam::camera::rh::{proj::vulkan, view::look_at_mat4};
use glam::{Mat4, Vec3};
use std::sync::Arc;
use translucent::ash::vk;
use translucent::gpu::Gpu;
use translucent::mesh::{Enclosure, enclosure};
use translucent::render::options::RendererOptions;
use translucent::render::renderer::Renderer;
use translucent::render::cull::hidden_faces;
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};
use translucent::{Change, DepthConvention, DepthTest, TargetDesc};

const RESOLUTION: usize = 96;

/// A marble `shape` on a floor, seen from `eye`, with one key light.
fn scene(shape: &str, eye: [f32; 3]) -> PreparedScene {
    let text = format!(
        r#"
[camera]
eye = [{}, {}, {}]
target = [0.0, 0.005, 0.0]
fov_y = 40.0
resolution = [{RESOLUTION}, {RESOLUTION}]

[[object]]
shape = {shape}
transform = {{ fit = 0.02, translate = [0.0, 0.006, 0.0] }}
material = {{ type = "translucent", preset = "marble", mm_per_unit = 1000.0 }}

[[object]]
shape = {{ type = "plane", size = 0.2, divisions = 4 }}
material = {{ type = "opaque", albedo = [0.5, 0.5, 0.5] }}
casts_shadow = false

[[light]]
type = "directional"
direction = [0.4, 0.8, 0.3]
irradiance = [3.0, 3.0, 3.0]

[sampling]
method = "turk"
count = 300
"#,
        eye[0], eye[1], eye[2]
    );
    // Mesh paths are absolute; the base folder only makes them files rather than embedded assets.
    let scene = Scene::parse(&text, "culling.toml", Some(std::env::temp_dir())).unwrap();
    PreparedScene::new(&scene, &Overrides::default()).unwrap()
}

const SPHERE: &str = r#"{ type = "sphere", radius = 1.0, divisions = 16 }"#;

/// The image with hidden faces culled (the planner's plan: from the camera and from the light)
/// and with every face drawn, from one renderer, and the faces the first object's drawn level
/// had culled from the camera.
fn images(gpu: &Arc<Gpu>, prepared: PreparedScene, depth: DepthTest) -> (Vec<u8>, Vec<u8>, vk::CullModeFlags) {
    let options = RendererOptions { depth, ..RendererOptions::default() };
    let mut renderer = Renderer::with_options(gpu, prepared, TargetDesc::Own, options).unwrap();
    let plan = renderer.plan(Change::Everything);
    assert!(plan.cull_hidden_faces, "the planner's plan culls");
    renderer.frame(&plan).unwrap();
    let culled = renderer.image().unwrap().0;
    let object = &renderer.scene().objects[0];
    let level = &object.levels[plan.level(0).min(object.levels.len() - 1)];
    let positions = object.mesh.positions();
    let camera = renderer.camera();
    let view_proj = camera.projection * camera.view;
    let faces =
        hidden_faces(enclosure(positions, &level.triangles), level.bounds(positions), view_proj, depth.convention);
    // Everything again: the shadow maps, splat and gather too, every face drawn.
    let mut plan = renderer.plan(Change::Everything);
    plan.cull_hidden_faces = false;
    renderer.frame(&plan).unwrap();
    (culled, renderer.image().unwrap().0, faces)
}

/// Pixels whose colour differs, and the largest difference in 8-bit levels.
fn differences(a: &[u8], b: &[u8]) -> (usize, u8) {
    let pixels = a.chunks(4).zip(b.chunks(4)).filter(|(p, q)| p != q).count();
    (pixels, a.iter().zip(b).map(|(p, q)| p.abs_diff(*q)).max().unwrap_or(0))
}

/// Culled against whole: at most a few silhouette pixels differ, where a back face ties with
/// the front face in depth and, drawn later, won the tie.
fn assert_same_image(culled: &[u8], whole: &[u8], case: &str) {
    let (pixels, largest) = differences(culled, whole);
    eprintln!("{case}: {pixels} of {} pixels differ, by at most {largest}/255", RESOLUTION * RESOLUTION);
    assert!(pixels * 200 <= RESOLUTION * RESOLUTION, "{case}: {pixels} pixels differ (largest {largest}/255)");
}

#[test]
fn culling_a_closed_surfaces_hidden_faces_leaves_the_image_as_drawing_every_face() {
    with_gpu(|gpu| {
        let outside = [0.0, 0.03, 0.06];
        for depth in [DepthTest::STANDARD, DepthTest::REVERSED] {
            let (culled, whole, faces) = images(gpu, scene(SPHERE, outside), depth);
            assert_eq!(faces, vk::CullModeFlags::BACK, "{depth:?}: a sphere wound outward hides its back faces");
            assert_same_image(&culled, &whole, &format!("sphere, {:?}", depth.convention));
        }
    });
}

#[test]
fn an_inward_wound_surface_hides_its_front_faces_and_draws_the_same_image() {
    // bunny-1.8k is closed; its faces reversed wind it inward.
    let text = std::fs::read_to_string(asset("bunny-1.8k.obj")).unwrap();
    let reversed: String = text
        .lines()
        .map(|l| match l.strip_prefix("f ") {
            Some(rest) => format!("f {}\n", rest.split_whitespace().rev().collect::<Vec<_>>().join(" ")),
            None => format!("{l}\n"),
        })
        .collect();
    let path = temp_dir("culling").join("bunny-inward.obj");
    std::fs::write(&path, reversed).unwrap();
    let mesh = |path: &std::path::Path| format!(r#"{{ type = "mesh", path = "{}" }}"#, path.display());
    with_gpu(|gpu| {
        let (culled, whole, faces) = images(gpu, scene(&mesh(&path), [0.0, 0.03, 0.06]), DepthTest::STANDARD);
        assert_eq!(faces, vk::CullModeFlags::FRONT);
        assert_same_image(&culled, &whole, "bunny wound inward");
    });
}

#[test]
fn a_camera_inside_a_closed_surface_culls_nothing() {
    with_gpu(|gpu| {
        // The sphere's centre is at (0, 0.006, 0), radius 0.01: the eye inside it.
        let (culled, whole, faces) = images(gpu, scene(SPHERE, [0.0, 0.008, 0.002]), DepthTest::STANDARD);
        assert_eq!(faces, vk::CullModeFlags::NONE);
        assert_eq!(differences(&culled, &whole).0, 0);
    });
}

/// A unit cube's corners as bounds, wound outward, seen through `view_proj`.
fn cube_faces(view_proj: Mat4, enclosure: Enclosure, convention: DepthConvention) -> vk::CullModeFlags {
    hidden_faces(enclosure, (Vec3::splat(-1.0), Vec3::splat(1.0)), view_proj, convention)
}

#[test]
fn the_faces_culled_follow_the_winding_the_mirror_and_the_near_plane() {
    // Vulkan's clip space, y down, as the renderer's cameras make it (scene::Camera::projection).
    let projection = vulkan::perspective(1.0, 1.0, 0.1, 100.0);
    let view = look_at_mat4(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y);
    let standard = projection * view;
    assert_eq!(cube_faces(standard, Enclosure::Outward, DepthConvention::Standard), vk::CullModeFlags::BACK);
    assert_eq!(cube_faces(standard, Enclosure::Inward, DepthConvention::Standard), vk::CullModeFlags::FRONT);
    assert_eq!(cube_faces(standard, Enclosure::Open, DepthConvention::Standard), vk::CullModeFlags::NONE);
    // A mirror in the view turns screen winding over.
    let mirrored = projection * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)) * view;
    assert_eq!(cube_faces(mirrored, Enclosure::Outward, DepthConvention::Standard), vk::CullModeFlags::FRONT);
    // Reversed-Z turns depth over, not the screen's winding.
    let reverse = Mat4::from_cols(
        glam::Vec4::X,
        glam::Vec4::Y,
        glam::Vec4::new(0.0, 0.0, -1.0, 0.0),
        glam::Vec4::new(0.0, 0.0, 1.0, 1.0),
    );
    assert_eq!(cube_faces(reverse * standard, Enclosure::Outward, DepthConvention::Reversed), vk::CullModeFlags::BACK);
    // The near plane cuts the cube (the eye 1.05 from its centre, 0.1 near): nothing culled.
    let close = projection * look_at_mat4(Vec3::new(0.0, 0.0, 1.05), Vec3::ZERO, Vec3::Y);
    assert_eq!(cube_faces(close, Enclosure::Outward, DepthConvention::Standard), vk::CullModeFlags::NONE);
    // The cube behind the eye: nothing of it in front, nothing culled (it is clipped whole).
    let behind = projection * look_at_mat4(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, 10.0), Vec3::Y);
    assert_eq!(cube_faces(behind, Enclosure::Outward, DepthConvention::Standard), vk::CullModeFlags::NONE);
}

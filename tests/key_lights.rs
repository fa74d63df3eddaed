//! The shading and splat passes unroll their loops over a few key lights
//! (`shade::unrolled_key_lights`, a specialization constant) and loop at run time over more. The
//! claim: both give the same image (the sphere's exitance comes through the splat).

mod common;

use common::*;
use translucent::render::renderer::Renderer;
use translucent::render::shade::{MAX_UNROLLED_KEY_LIGHTS, unrolled_key_lights};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

/// A marble sphere on a floor under `lights` directional key lights from different sides, the
/// last of them black when `black_last`.
fn scene(lights: usize, black_last: bool) -> PreparedScene {
    let mut text = String::from(
        r#"
[camera]
eye = [0.0, 0.03, 0.06]
target = [0.0, 0.005, 0.0]
fov_y = 40.0
resolution = [96, 96]

[[object]]
shape = { type = "sphere", radius = 0.01, divisions = 16 }
transform = { translate = [0.0, 0.01, 0.0] }
material = { type = "translucent", preset = "marble", mm_per_unit = 1000.0 }

[[object]]
shape = { type = "plane", size = 0.2, divisions = 4 }
material = { type = "opaque", albedo = [0.5, 0.5, 0.5] }
casts_shadow = false

[sampling]
method = "turk"
count = 300
"#,
    );
    for i in 0..lights {
        let angle = i as f32 * 1.3;
        let irradiance = if black_last && i + 1 == lights { 0.0 } else { 1.0 };
        text += &format!(
            "\n[[light]]\ntype = \"directional\"\ndirection = [{}, 0.7, {}]\nirradiance = [{irradiance}, {irradiance}, {irradiance}]\n",
            angle.cos(),
            angle.sin()
        );
    }
    PreparedScene::new(&Scene::parse(&text, "key_lights.toml", None).unwrap(), &Overrides::default()).unwrap()
}

#[test]
fn key_lights_unrolled_draw_what_the_run_time_loop_draws() {
    let n = MAX_UNROLLED_KEY_LIGHTS as usize;
    assert_eq!(unrolled_key_lights(MAX_UNROLLED_KEY_LIGHTS), MAX_UNROLLED_KEY_LIGHTS);
    assert_eq!(unrolled_key_lights(MAX_UNROLLED_KEY_LIGHTS + 1), 0, "past the limit the loop runs at run time");
    with_gpu(|gpu| {
        let image = |prepared| {
            let mut renderer = Renderer::new(gpu, prepared).unwrap();
            renderer.frame(&renderer.plan(translucent::Change::Everything)).unwrap();
            renderer.image().unwrap().0
        };
        // The same light, n of them unrolled, or n + 1 looped over with a black one last: a
        // black light adds exactly zero, so the images are the same byte for byte.
        let unrolled = image(scene(n, false));
        let looped = image(scene(n + 1, true));
        assert_eq!(unrolled, looped, "the unrolled and the looped shading differ");
        // And the lights do shade: one fewer changes the image.
        assert_ne!(image(scene(n - 1, false)), unrolled, "the last key light changed nothing");
    });
}

//! The scene parser and its checks (`Scene::parse`), then, for scenes cheap enough to prepare
//! (built-in shapes only, few divisions and samples), the CPU preparation that runs before any
//! GPU work (`PreparedScene::new`: shapes, transforms, materials, sample placement, lights and
//! shadow matrices). Everything a prepared scene hands to the GPU must be finite.
#![no_main]

use libfuzzer_sys::fuzz_target;
use translucent::scene::build::{Overrides, PreparedScene};
use translucent::scene::lights::LightKind;
use translucent::scene::{Light, Scene, Shape};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(scene) = Scene::parse(text, "fuzz.toml", None) else { return };
    let file = &scene.file;
    // The checks promise a camera the renderer can use.
    assert!(file.camera.view().is_finite(), "camera passed the checks but its view matrix is not finite");
    let cheap_shapes = file.objects.iter().all(|o| match o.shape {
        Shape::Mesh { .. } => false,
        Shape::Plane { divisions, .. } | Shape::Sphere { divisions, .. } => divisions <= 32,
    });
    // The built-in scene (base `None`) resolves maps among embedded assets: no file is read.
    let cheap_lights = file.lights.iter().all(|l| match l {
        Light::Environment { directions, .. } => *directions <= 64,
        _ => true,
    });
    // Without a count the error target would choose one, up to tens of thousands: cap it.
    if !(cheap_shapes && cheap_lights && file.objects.len() <= 4 && file.sampling.count.unwrap_or(0) <= 64) {
        return;
    }
    let overrides = Overrides { samples: file.sampling.count.is_none().then_some(64), ..Overrides::default() };
    let Ok(prepared) = PreparedScene::new(&scene, &overrides) else { return };
    for o in &prepared.objects {
        assert!(o.mesh.positions().iter().all(|p| p.is_finite()), "{}: non-finite position", o.name);
        for s in &o.samples {
            assert!(s.position.is_finite() && s.normal.is_finite() && s.area.is_finite(), "{}: bad sample", o.name);
        }
    }
    assert!(prepared.bounds.0.is_finite() && prepared.bounds.1.is_finite(), "bounds {:?}", prepared.bounds);
    let (centre, radius) = prepared.bounds;
    assert!(file.camera.projection(centre, radius).is_finite(), "camera projection is not finite");
    for l in &prepared.lights {
        let finite = match l.kind {
            LightKind::Directional { direction, irradiance } => direction.is_finite() && irradiance.is_finite(),
            LightKind::Point { position, intensity } => position.is_finite() && intensity.is_finite(),
            LightKind::Spot { position, axis, intensity, cos_outer, cos_inner } => {
                position.is_finite()
                    && axis.is_finite()
                    && intensity.is_finite()
                    && cos_outer.is_finite()
                    && cos_inner.is_finite()
            }
        };
        assert!(finite, "light from light[{}] is not finite: {:?}", l.source, l.kind);
        assert!(l.shadow_matrix.is_finite(), "light[{}]: non-finite shadow matrix", l.source);
        assert!(l.normal_offset.is_finite(), "light[{}]: non-finite normal offset", l.source);
    }
});

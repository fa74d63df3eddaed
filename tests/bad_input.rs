//! Bad input through the command line fails cleanly: exit status 1 (2 for a malformed command
//! line, which clap reports), a message that names the file, line, key, flag or device limit, no
//! panic, no validation message, and every output file that existed before left untouched.
//! Each test here is one defect found by probing the CLI (issue "Hard cases stay stable"), with
//! the class of input around it.

mod common;

use common::{subcommand, temp_dir, text, translucent};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// A small scene: one translucent sphere lit by a directional light, `extra` appended (TOML),
/// `replace` pairs applied to the base text first.
fn sphere_scene(dir: &Path, name: &str, replace: &[(&str, &str)], extra: &str) -> PathBuf {
    let mut text = String::from(
        r#"[camera]
eye = [0.0, 0.0, 0.1]
target = [0.0, 0.0, 0.0]
fov_y = 30.0
resolution = [48, 48]

[[object]]
shape = { type = "sphere", radius = 0.01, divisions = 12 }
material = { type = "translucent", preset = "marble", mm_per_unit = 1000.0 }

[[light]]
type = "directional"
direction = [0.3, 0.5, 1.0]
irradiance = [1.0, 1.0, 1.0]

[sampling]
method = "random"
count = 32

[render]
exposure = 1.0
"#,
    );
    for (from, to) in replace {
        assert!(text.contains(from), "{from} not in the base scene");
        text = text.replacen(from, to, 1);
    }
    text.push_str(extra);
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Exit status 1, no panic, no validation message; returns stderr.
fn fails(out: &Output) -> String {
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "panic instead of an error: {stderr}");
    assert!(!stderr.contains("[vulkan"), "validation messages: {stderr}");
    stderr
}

fn succeeds(out: &Output) -> String {
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "stderr: {stderr}");
    assert!(!stderr.contains("[vulkan"), "validation messages: {stderr}");
    stderr
}

/// Files in `dir` whose name ends in `.partial` (left-over temporaries).
fn partials(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".partial"))
        .collect()
}

/// RGBA8 pixels of a PNG.
fn png_pixels(path: &Path) -> Vec<u8> {
    image::open(path).unwrap().to_rgba8().into_raw()
}

#[test]
fn a_failing_render_touches_no_output_and_names_the_path_given() {
    let dir = temp_dir("all-or-nothing");
    let scene = sphere_scene(&dir, "s.toml", &[], "");
    let png = dir.join("out.png");
    let exr = dir.join("out.exr");
    std::fs::write(&png, "old png").unwrap();
    std::fs::write(&exr, "old exr").unwrap();
    let args = ["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap(), "--exr", exr.to_str().unwrap()];
    // The PLY is written last, after the PNG and EXR: a folder where its temporary file goes
    // makes that write fail after the others were written.
    let ply = dir.join("blocked.ply");
    let blocker = dir.join(".blocked.ply.partial");
    std::fs::create_dir(&blocker).unwrap();
    let out = translucent(&[&args[..], &["--export-exitance", ply.to_str().unwrap()]].concat(), &[]);
    let stderr = fails(&out);
    assert!(stderr.contains("blocked.ply"), "{stderr}");
    assert!(!stderr.contains(".partial"), "the error names a temporary file: {stderr}");
    assert_eq!(std::fs::read_to_string(&png).unwrap(), "old png", "the PNG was replaced");
    assert_eq!(std::fs::read_to_string(&exr).unwrap(), "old exr", "the EXR was replaced");
    std::fs::remove_dir(&blocker).unwrap();
    assert!(partials(&dir).is_empty(), "temporaries left: {:?}", partials(&dir));
    // A folder in an output's place is refused before rendering.
    let folder = dir.join("a-folder.ply");
    std::fs::create_dir(&folder).unwrap();
    let out = translucent(&[&args[..], &["--export-exitance", folder.to_str().unwrap()]].concat(), &[]);
    assert!(fails(&out).contains("a-folder.ply: it is a folder"));
    assert_eq!(std::fs::read_to_string(&png).unwrap(), "old png");

    // A folder that does not exist is caught before rendering, for any of the outputs.
    let missing = dir.join("no-such-folder").join("x.exr");
    let out = translucent(
        &["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap(), "--exr", missing.to_str().unwrap()],
        &[],
    );
    let stderr = fails(&out);
    assert!(stderr.contains("no-such-folder"), "{stderr}");
    assert_eq!(std::fs::read_to_string(&png).unwrap(), "old png");

    // The same output named twice is refused.
    let out = translucent(
        &["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap(), "--exr", png.to_str().unwrap()],
        &[],
    );
    assert!(fails(&out).contains("two outputs"));

    // All requested outputs appear together when everything works.
    let ply = dir.join("exitance.ply");
    let out = translucent(&[&args[..], &["--export-exitance", ply.to_str().unwrap()]].concat(), &[]);
    succeeds(&out);
    assert_ne!(std::fs::read(&png).unwrap(), b"old png");
    assert_ne!(std::fs::read(&exr).unwrap(), b"old exr");
    assert!(ply.is_file());
    assert!(partials(&dir).is_empty());
}

#[test]
fn scenes_beyond_the_device_limits_are_refused_before_gpu_work_naming_the_setting() {
    let dir = temp_dir("limits");
    let png = dir.join("out.png");
    std::fs::write(&png, "old").unwrap();
    let scene = sphere_scene(&dir, "s.toml", &[], "");
    let render = |extra: &[&str]| {
        translucent(&[&["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap()], extra].concat(), &[])
    };
    // The tone map's output buffer (4 bytes a pixel) passes maxStorageBufferRange (lavapipe:
    // 128 MiB) at 8192x4097, and 16384x16384 goes far past it.
    for resolution in ["8192x4097", "16384x16384"] {
        let stderr = fails(&render(&["--resolution", resolution]));
        assert!(stderr.contains("camera.resolution") && stderr.contains("maxStorageBufferRange"), "{stderr}");
    }
    // One shadow layer per light: 2,049 lights pass maxImageArrayLayers (2,048 on lavapipe).
    let mut lights = String::new();
    for i in 0..2049 {
        let a = i as f32 * 0.001;
        lights.push_str(&format!(
            "\n[[light]]\ntype = \"directional\"\ndirection = [{}, 1.0, {}]\nirradiance = [0.001, 0.001, 0.001]\n",
            a.cos(),
            a.sin()
        ));
    }
    let many = sphere_scene(&dir, "many.toml", &[], &lights);
    let out = translucent(&["render", many.to_str().unwrap(), "-o", png.to_str().unwrap()], &[]);
    let stderr = fails(&out);
    assert!(stderr.contains("shadow maps") && stderr.contains("maxImageArrayLayers"), "{stderr}");
    // 256 shadow maps of 8192^2 texels: 32 GiB in one image.
    let huge = sphere_scene(
        &dir,
        "huge.toml",
        &[("exposure = 1.0", "exposure = 1.0\nshadow_map_size = 8192")],
        "\n[[light]]\ntype = \"environment\"\ndirections = 256\n",
    );
    let out = translucent(&["render", huge.to_str().unwrap(), "-o", png.to_str().unwrap()], &[]);
    let stderr = fails(&out);
    assert!(stderr.contains("render.shadow_map_size") && stderr.contains("does not fit"), "{stderr}");
    assert_eq!(std::fs::read_to_string(&png).unwrap(), "old");
    // --samples keeps the scene's limit on sampling.count.
    let stderr = fails(&render(&["--samples", "10000000"]));
    assert!(stderr.contains("--samples 10000000") && stderr.contains("1000000"), "{stderr}");
}

/// Spawn the binary with its stdout closed by the reader before it writes.
fn with_closed_stdout(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_translucent"))
        .args(args)
        .env("TRANSLUCENT_VALIDATION", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let mut stderr = Vec::new();
    child.stderr.take().unwrap().read_to_end(&mut stderr).unwrap();
    let status = child.wait().unwrap();
    Output { status, stdout: Vec::new(), stderr }
}

#[test]
fn a_closed_stdout_ends_a_command_quietly() {
    let dir = temp_dir("closed-stdout");
    let scene = sphere_scene(&dir, "s.toml", &[], "");
    let png = dir.join("out.png");
    let mesh = common::asset("bunny-1.8k.obj");
    for args in [
        vec!["devices"],
        vec!["devices", "--json"],
        vec!["material", "marble"],
        vec!["sample", mesh.to_str().unwrap(), "--method", "random", "--count", "50"],
        vec!["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap(), "--timings"],
    ] {
        let out = with_closed_stdout(&args);
        let stderr = text(&out.stderr);
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
    }
    assert!(png.is_file(), "render --timings wrote its image before the closed stdout");
}

#[test]
fn very_bright_input_stays_finite_and_white_not_black() {
    let dir = temp_dir("bright");
    let count_white = |png: &Path| png_pixels(png).chunks(4).filter(|p| p[0] == 255 && p[1] == 255).count();
    type Case<'a> = (&'a str, &'a [(&'a str, &'a str)]);
    let cases: [Case; 3] = [
        ("irradiance 1e30", &[("irradiance = [1.0, 1.0, 1.0]", "irradiance = [1e30, 1e30, 1e30]")]),
        ("exposure 1e30", &[("exposure = 1.0", "exposure = 1e30")]),
        ("background 3e38", &[("exposure = 1.0", "exposure = 1.0\nbackground = [3e38, 3e38, 3e38]")]),
    ];
    for (what, replace) in cases {
        let scene = sphere_scene(&dir, "bright.toml", replace, "");
        let png = dir.join("bright.png");
        let exr = dir.join("bright.exr");
        let out = translucent(
            &["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap(), "--exr", exr.to_str().unwrap()],
            &[],
        );
        succeeds(&out);
        // The sphere covers about a fifth of the 48x48 image: at least that much is white.
        let white = count_white(&png);
        assert!(white > 48 * 48 / 10, "{what}: only {white} white pixels");
        let hdr = image::open(&exr).unwrap().to_rgba32f();
        assert!(hdr.pixels().all(|p| p.0.iter().all(|v| v.is_finite() && *v >= 0.0)), "{what}: EXR not finite");
    }
}

/// A 16x8 Radiance .hdr of constant radiance `value` above the horizon, 1e-3 below.
fn bright_sky(path: &Path, value: f32) {
    let mut img = image::Rgb32FImage::new(16, 8);
    for (_, y, p) in img.enumerate_pixels_mut() {
        let v = if y < 4 { value } else { 1e-3 };
        *p = image::Rgb([v, v, v]);
    }
    image::DynamicImage::ImageRgb32F(img).save_with_format(path, image::ImageFormat::Hdr).unwrap();
}

#[test]
fn a_very_bright_environment_map_still_lights_the_object() {
    let dir = temp_dir("bright-sky");
    bright_sky(&dir.join("sky.hdr"), 1e20);
    let scene = sphere_scene(
        &dir,
        "sky.toml",
        &[("irradiance = [1.0, 1.0, 1.0]", "irradiance = [0.0, 0.0, 0.0]")],
        "\n[[light]]\ntype = \"environment\"\nmap = \"sky.hdr\"\ndirections = 4\n",
    );
    let ply = dir.join("e.ply");
    let out = translucent(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            dir.join("e.png").to_str().unwrap(),
            "--export-exitance",
            ply.to_str().unwrap(),
        ],
        &[],
    );
    succeeds(&out);
    let body = std::fs::read_to_string(&ply).unwrap();
    let values: Vec<f64> = body
        .split("end_header\n")
        .nth(1)
        .unwrap()
        .lines()
        .flat_map(|l| l.split_whitespace().skip(3).map(|v| v.parse::<f64>().unwrap()))
        .collect();
    assert!(values.iter().all(|v| v.is_finite() && *v >= 0.0));
    let lit = values.iter().filter(|v| **v > 1e15).count();
    assert!(lit > values.len() / 4, "only {lit} of {} exitance values are lit by a 1e20 sky", values.len());
}

#[test]
fn exporting_exitance_from_the_pixel_gather_is_refused() {
    let dir = temp_dir("pixel-export");
    let scene = sphere_scene(&dir, "s.toml", &[], "");
    let png = dir.join("out.png");
    std::fs::write(&png, "old").unwrap();
    let out = translucent(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
            "--gather",
            "pixel",
            "--export-exitance",
            dir.join("e.ply").to_str().unwrap(),
        ],
        &[],
    );
    let stderr = fails(&out);
    assert!(stderr.contains("--export-exitance") && stderr.contains("--gather vertex or sparse"), "{stderr}");
    assert_eq!(std::fs::read_to_string(&png).unwrap(), "old");
    assert!(!dir.join("e.ply").exists());
}

#[test]
fn absurd_sizes_distances_and_devices_are_errors_naming_them() {
    let dir = temp_dir("absurd");
    let png = dir.join("out.png");
    let render = |scene: &Path| translucent(&["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap()], &[]);
    type Case<'a> = (&'a str, &'a [(&'a str, &'a str)], &'a str);
    let cases: [Case; 4] = [
        ("radius 1e30", &[("radius = 0.01", "radius = 1e30")], "object[0].shape"),
        ("scale 1e30", &[("divisions = 12 }", "divisions = 12 }\ntransform = { scale = 1e30 }")], "farther than"),
        ("eye 4e19 away", &[("eye = [0.0, 0.0, 0.1]", "eye = [0.0, 0.0, 4e19]")], "camera.eye"),
        ("light type error", &[("irradiance = [1.0, 1.0, 1.0]", "irradiance = \"bright\"")], "light[0].irradiance"),
    ];
    for (what, replace, expected) in cases {
        let scene = sphere_scene(&dir, "absurd.toml", replace, "");
        let stderr = fails(&render(&scene));
        assert!(stderr.contains(expected), "{what}: {stderr}");
        assert!(!png.exists(), "{what}: an image was written");
    }
    // A type error inside an inline table names the key and its line, not only the table.
    let scene = sphere_scene(&dir, "shape.toml", &[("radius = 0.01", "radius = \"big\"")], "");
    let stderr = fails(&render(&scene));
    assert!(stderr.contains("line 8") && stderr.contains("object[0].shape.radius"), "{stderr}");
    let scene = sphere_scene(&dir, "material.toml", &[("preset = \"marble\"", "preset = 5")], "");
    let stderr = fails(&render(&scene));
    assert!(stderr.contains("line 9") && stderr.contains("object[0].material.preset"), "{stderr}");

    // `sample --scale` past the coordinate limit: no infinite areas written.
    let points = dir.join("points.ply");
    let mesh = common::asset("bunny-1.8k.obj");
    let out = subcommand(
        "sample",
        &[
            mesh.to_str().unwrap(),
            "--method",
            "random",
            "--count",
            "10",
            "--scale",
            "1e30",
            "-o",
            points.to_str().unwrap(),
        ],
    );
    assert!(fails(&out).contains("farther than"));
    assert!(!points.exists());

    // `devices --device` with no match is the same error as for every other command.
    let stderr = fails(&subcommand("devices", &["--device", "nonsense"]));
    assert!(stderr.contains("no Vulkan device matches"), "{stderr}");
    // A malformed command line is clap's usage error, status 2, listing what is accepted.
    let out = subcommand("render", &["--gather", "nope"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("vertex, pixel, sparse"));
}

#[test]
fn an_object_far_from_the_origin_is_warned_about_with_the_figure() {
    let dir = temp_dir("far");
    let scene = sphere_scene(
        &dir,
        "far.toml",
        &[
            ("eye = [0.0, 0.0, 0.1]", "eye = [1000.0, 0.0, 0.1]"),
            ("target = [0.0, 0.0, 0.0]", "target = [1000.0, 0.0, 0.0]"),
            ("divisions = 12 }", "divisions = 12 }\ntransform = { translate = [1000.0, 0.0, 0.0] }"),
        ],
        "",
    );
    let out = translucent(&["render", scene.to_str().unwrap(), "-o", dir.join("far.png").to_str().unwrap()], &[]);
    let stderr = succeeds(&out);
    assert!(
        stderr.contains("object[0]") && stderr.contains("from the origin") && stderr.contains("% of its size"),
        "{stderr}"
    );
    // Near the origin: no warning.
    let near = sphere_scene(&dir, "near.toml", &[], "");
    let out = translucent(&["render", near.to_str().unwrap(), "-o", dir.join("near.png").to_str().unwrap()], &[]);
    assert!(!succeeds(&out).contains("from the origin"));
}

#[test]
fn an_interrupted_write_leaves_no_temporary_file() {
    let dir = temp_dir("interrupt");
    // Big enough that writing the PNG and EXR takes a noticeable time.
    let scene = sphere_scene(&dir, "s.toml", &[("resolution = [48, 48]", "resolution = [3072, 3072]")], "");
    let png = dir.join("big.png");
    std::fs::write(&png, "old").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_translucent"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
            "--exr",
            dir.join("big.exr").to_str().unwrap(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until a temporary file exists, then interrupt.
    let start = std::time::Instant::now();
    while partials(&dir).is_empty() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the render ended ({status}) before a temporary file was seen");
        }
        assert!(start.elapsed().as_secs() < 120, "no temporary file appeared");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    // SAFETY: sending a signal to our own child process.
    let pid = child.id().to_string();
    assert!(Command::new("kill").args(["-INT", &pid]).status().unwrap().success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "exit status after SIGINT");
    assert!(partials(&dir).is_empty(), "temporaries left: {:?}", partials(&dir));
    assert_eq!(std::fs::read_to_string(&png).unwrap(), "old");
}

#[test]
fn an_environment_map_whose_header_claims_millions_of_texels_is_refused_naming_the_limit() {
    use translucent::scene::lights::{Environment, EnvironmentError, MAX_ENVIRONMENT_SIDE, MAX_ENVIRONMENT_TEXELS};
    // 881 bytes of tiled EXR whose header says 7733242x4: decoding it took 10 s (found by the
    // environment fuzzer, now in its corpus).
    let bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/fuzz/corpus/environment/regression-exr-7733242x4"))
        .unwrap();
    match Environment::from_bytes(&bytes, "huge.exr") {
        Err(e @ EnvironmentError::TooLarge { width: 7733242, height: 4, limit: MAX_ENVIRONMENT_TEXELS, .. }) => {
            let message = e.to_string();
            assert!(message.contains("huge.exr") && message.contains("7733242x4"), "{message}");
            assert!(message.contains(&MAX_ENVIRONMENT_SIDE.to_string()), "{message}");
        }
        other => panic!("expected TooLarge, got {:?}", other.map(|e| (e.width, e.height))),
    }
}

/// A value of the wrong type in `[render]` names its key once, with its line (issue 29, defect
/// 6: it read `render.level_of_detail.level_of_detail`), as in every other table.
#[test]
fn a_type_error_in_render_names_its_key_once() {
    let dir = temp_dir("render-type");
    let png = dir.join("out.png");
    let cases = [
        ("level_of_detail = \"yes\"", "render.level_of_detail"),
        ("gather_epsilon = \"small\"", "render.gather_epsilon"),
        ("exposure = [1.0]", "render.exposure"),
    ];
    for (line, key) in cases {
        let scene = sphere_scene(&dir, "render.toml", &[("exposure = 1.0", line)], "");
        let stderr = fails(&translucent(&["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap()], &[]));
        assert!(stderr.contains(&format!("at key `{key}`")) && stderr.contains("line 21"), "{line}: {stderr}");
        let last = key.rsplit('.').next().unwrap();
        assert!(!stderr.contains(&format!("{key}.{last}")), "{line}: the key named twice: {stderr}");
        assert!(!png.exists(), "{line}: an image was written");
    }
}

/// A camera nearer a mesh in view than the near plane (which the scene's depth sets) is warned
/// about with the figures: the image shows nothing of the mesh there (issue 29: a camera 1e-5
/// units from a sphere beside a 10-unit floor drew black without a word). From 0.05 units, no
/// warning.
#[test]
fn a_camera_whose_near_plane_clips_an_object_in_view_is_warned_about() {
    let dir = temp_dir("near-plane");
    let floor = "\n[[object]]\nshape = { type = \"plane\", size = 10.0 }\ntransform = { translate = [0.0, -0.02, 0.0] }\n\
                 material = { type = \"opaque\", albedo = [0.5, 0.5, 0.5] }\n";
    let close = sphere_scene(&dir, "close.toml", &[("eye = [0.0, 0.0, 0.1]", "eye = [0.0, 0.0, 0.01001]")], floor);
    let out = translucent(&["render", close.to_str().unwrap(), "-o", dir.join("close.png").to_str().unwrap()], &[]);
    let stderr = succeeds(&out);
    assert!(stderr.contains("object[0]") && stderr.contains("nearer than the near plane"), "{stderr}");
    assert!(!stderr.contains("object[1]"), "the floor is not clipped where the camera looks: {stderr}");
    let far = sphere_scene(&dir, "far.toml", &[("eye = [0.0, 0.0, 0.1]", "eye = [0.0, 0.0, 0.06]")], floor);
    let out = translucent(&["render", far.to_str().unwrap(), "-o", dir.join("far.png").to_str().unwrap()], &[]);
    assert!(!succeeds(&out).contains("near plane"));
}

/// With the camera inside an object, at its centre, the planner's text says so instead of
/// `inf px` and `NaN px` (issue 29).
#[test]
fn the_plan_says_when_the_camera_is_inside_an_object() {
    let dir = temp_dir("inside");
    let scene = sphere_scene(
        &dir,
        "inside.toml",
        &[
            ("eye = [0.0, 0.0, 0.1]", "eye = [0.0, 0.0, 0.0]"),
            ("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, -1.0]"),
        ],
        "",
    );
    let out = subcommand("plan", &[scene.to_str().unwrap()]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(stdout.contains("the camera is inside the object") || stdout.contains("inside them"), "{stdout}");
    assert!(!stdout.contains("inf px") && !stdout.contains("NaN"), "{stdout}");
}

//! The study's 2 cm marble sphere as OBJ files, with and without latitude-longitude texture
//! coordinates, and a scene for each: the texture gather on the mesh's own UVs against our
//! charts of the same mesh (docs/STUDY.md, "The atlas").
//!
//! `cargo run --release --example uv_sphere -- DIR` writes `DIR/sphere-uv.obj`,
//! `DIR/sphere-charts.obj`, `DIR/sphere-uv.toml` and `DIR/sphere-charts.toml`; then
//! `translucent study DIR/sphere-uv.toml -o OUT --samplers turk --seeds 1 --counts 64,256,1024
//! --gathers texture:R` for each.

use std::f32::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

const RADIUS: f32 = 0.01;

/// Latitude-longitude coordinates of each corner of triangle `t`: u runs with the longitude
/// (a corner on the seam takes 1 in a triangle whose others are past half way), v up with the
/// latitude, and a pole corner takes the mean u of the other two.
fn corner_uvs(corners: [glam::Vec3; 3]) -> [[f32; 2]; 3] {
    let pole = |p: glam::Vec3| p.y.abs() > RADIUS * 0.9999;
    let mut uv = corners.map(|p| {
        let u = p.z.atan2(p.x) / (2.0 * PI);
        [if u < 0.0 { u + 1.0 } else { u }, 1.0 - (p.y / RADIUS).clamp(-1.0, 1.0).acos() / PI]
    });
    let others: Vec<f32> = (0..3).filter(|&i| !pole(corners[i])).map(|i| uv[i][0]).collect();
    if others.iter().any(|&u| u > 0.5) {
        for (i, c) in uv.iter_mut().enumerate() {
            if !pole(corners[i]) && c[0] < 1e-6 {
                c[0] = 1.0;
            }
        }
    }
    for (i, c) in uv.clone().iter().enumerate() {
        if pole(corners[i]) {
            let rest: Vec<f32> = (0..3).filter(|&j| j != i).map(|j| uv[j][0]).collect();
            uv[i] = [rest.iter().sum::<f32>() / rest.len() as f32, c[1]];
        }
    }
    uv
}

fn obj(with_uvs: bool) -> String {
    let mesh = translucent::mesh::shapes::sphere(RADIUS, 24).expect("a sphere");
    let mut text = String::new();
    for p in mesh.positions() {
        writeln!(text, "v {} {} {}", p.x, p.y, p.z).unwrap();
    }
    for (t, tri) in mesh.triangles().iter().enumerate() {
        let [a, b, c] = tri.map(|v| v + 1);
        if with_uvs {
            for [u, v] in corner_uvs(tri.map(|v| mesh.positions()[v as usize])) {
                writeln!(text, "vt {u} {v}").unwrap();
            }
            let k = 3 * t + 1;
            writeln!(text, "f {a}/{k} {b}/{} {c}/{}", k + 1, k + 2).unwrap();
        } else {
            writeln!(text, "f {a} {b} {c}").unwrap();
        }
    }
    text
}

fn scene(mesh: &str) -> String {
    let sphere = std::fs::read_to_string("assets/scenes/sphere-marble.toml").expect("run from the repository root");
    sphere.replace(
        r#"shape = { type = "sphere", radius = 0.01, divisions = 24 }"#,
        &format!(r#"shape = {{ type = "mesh", path = "{mesh}" }}"#),
    )
}

fn main() {
    let dir = std::env::args().nth(1).unwrap_or_else(|| ".".into());
    let dir = Path::new(&dir);
    std::fs::create_dir_all(dir).expect("the output folder");
    for (name, with_uvs) in [("sphere-uv", true), ("sphere-charts", false)] {
        std::fs::write(dir.join(format!("{name}.obj")), obj(with_uvs)).expect("writing the OBJ");
        std::fs::write(dir.join(format!("{name}.toml")), scene(&format!("{name}.obj"))).expect("writing the scene");
        println!("wrote {}", dir.join(format!("{name}.toml")).display());
    }
}

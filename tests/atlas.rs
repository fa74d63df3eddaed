//! The texture gather's atlas (issue 48, part 4): a mesh's own texture coordinates are used
//! where they fit, charts of ours are cut where they do not, with the reason, and the charts
//! are packed tightly. CPU only.

mod common;

use common::{load_asset, subcommand, temp_dir, text, triangle_glb};
use translucent::mesh::atlas::{Atlas, AtlasSource, ChartsReason};
use translucent::mesh::{LoadOptions, Mesh};

/// An `n` x `n` grid of squares over the unit square in x and z, two triangles each, with the
/// texture coordinates `uv(x, z)` at each vertex, as OBJ text.
fn grid_obj(n: usize, uv: impl Fn(f32, f32) -> [f32; 2]) -> String {
    let mut obj = String::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (i as f32 / n as f32, j as f32 / n as f32);
            let [u, v] = uv(x, z);
            obj += &format!("v {x} 0 {z}\nvt {u} {v}\n");
        }
    }
    let at = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            obj += &format!("f {a}/{a} {d}/{d} {c}/{c}\nf {a}/{a} {c}/{c} {b}/{b}\n");
        }
    }
    obj
}

fn mesh(obj: &str) -> Mesh {
    Mesh::from_obj_text(obj, "grid.obj", &LoadOptions::default()).unwrap()
}

#[test]
fn a_mesh_with_its_own_uvs_keeps_them_and_its_texels_keep_its_area() {
    let mesh = mesh(&grid_obj(8, |x, z| [0.1 + 0.8 * x, 0.1 + 0.8 * z]));
    assert!(mesh.corner_uvs().is_some());
    let atlas = Atlas::new(&mesh, 64).unwrap();
    assert_eq!(atlas.source, AtlasSource::OwnUvs);
    // The grid's corner (0, 0, 0) has uv (0.1, 0.1): column 6, row (1 - 0.1) 64 = 57.6.
    let corner = mesh.positions().iter().position(|p| p.length() == 0.0).unwrap();
    assert_eq!(atlas.vertex_texel[corner], [6, 57]);
    let area: f64 = atlas.texels.iter().map(|t| t.area).sum();
    assert!((area - mesh.total_area()).abs() < 1e-9, "{area}");
    // 0.8 of the side in texels per unit.
    assert!((atlas.scale - 0.8 * 64.0).abs() < 1e-4, "{}", atlas.scale);
    // A texel's position is where its uv is on the grid.
    let t = &atlas.texels[atlas.texels.len() / 2];
    let u = (f64::from(t.coord[0]) + 0.5) / 64.0;
    assert!((f64::from(t.position.x) - (u - 0.1) / 0.8).abs() < 1e-5, "{t:?}");
}

#[test]
fn overlapping_or_tiled_uvs_and_none_at_all_fall_back_to_charts_saying_why() {
    // Mirrored halves: the left half folds onto the right one in texture space.
    let overlapping = mesh(&grid_obj(4, |x, z| [(2.0 * x - 1.0).abs(), z]));
    let atlas = Atlas::new(&overlapping, 64).unwrap();
    assert!(matches!(atlas.source, AtlasSource::Charts(ChartsReason::Overlapping { .. })), "{:?}", atlas.source);
    let tiled = mesh(&grid_obj(4, |x, z| [2.0 * x, z]));
    let atlas = Atlas::new(&tiled, 64).unwrap();
    assert!(matches!(atlas.source, AtlasSource::Charts(ChartsReason::OutsideUnitSquare { .. })));
    let bunny = load_asset("bunny-1.8k.obj");
    assert_eq!(Atlas::new(&bunny, 64).unwrap().source, AtlasSource::Charts(ChartsReason::NoUvs));
    assert!(atlas.charts >= 1 && !atlas.texels.is_empty());
}

#[test]
fn a_glb_primitives_texcoords_reach_the_atlas() {
    let positions = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let uvs = [[0.0f32, 0.0], [0.5, 0.0], [0.0, 0.5]];
    let glb = triangle_glb(positions, "TEXCOORD_0", "VEC2", uvs.as_flattened(), serde_json::json!({"mesh": 0}));
    let mesh = Mesh::from_gltf_slice(&glb, "uv.glb", None, &LoadOptions::default()).unwrap();
    let corners = mesh.corner_uvs().expect("TEXCOORD_0 read");
    assert_eq!(corners[0].map(|c| c.to_array()), uvs);
    assert_eq!(Atlas::new(&mesh, 32).unwrap().source, AtlasSource::OwnUvs);
}

/// Issue 48: the atlas of the built-in bunny (37.7k vertices) uses at least 60% of its texels at
/// the default 256x256 and at 128 and 512 (the charts' own shapes packed, not their boxes on
/// shelves: 24 to 30% there).
#[test]
fn the_built_in_bunny_atlas_uses_at_least_60_percent_of_its_texels() {
    let mesh = load_asset("bunny-37k.obj");
    for resolution in [128, 256, 512] {
        let atlas = Atlas::new(&mesh, resolution).unwrap();
        let share = atlas.texels.len() as f64 / f64::from(resolution * resolution);
        eprintln!("bunny-37k atlas {resolution}: {} charts, {:.1}% of texels used", atlas.charts, share * 100.0);
        assert!(share >= 0.6, "atlas {resolution}: {:.1}% of texels used", share * 100.0);
    }
}

/// `plan --json` says which layout each atlas took and why (issue 48: "a typed reason in plan").
#[test]
fn plan_says_whether_an_atlas_took_the_meshs_own_uvs_or_charts_and_why() {
    let dir = temp_dir("atlas-plan");
    let with = grid_obj(8, |x, z| [0.1 + 0.8 * x, 0.1 + 0.8 * z]);
    let without: String = with
        .lines()
        .filter(|l| !l.starts_with("vt"))
        .map(|l| {
            // `f a/a b/b c/c` without texture coordinates: `f a b c`.
            if l.starts_with('f') {
                l.split(' ').map(|w| w.split('/').next().unwrap()).collect::<Vec<_>>().join(" ")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    for (name, obj, source, why) in [
        ("uv", with, "own_uvs", serde_json::Value::Null),
        ("plain", without, "charts", serde_json::json!("the mesh has no texture coordinates")),
    ] {
        std::fs::write(dir.join(format!("{name}.obj")), obj).unwrap();
        let scene = format!(
            "[camera]\neye = [0.5, 1.5, 0.5]\ntarget = [0.5, 0.0, 0.5]\nup = [0.0, 0.0, -1.0]\n\n[[object]]\n\
             shape = {{ type = \"mesh\", path = \"{name}.obj\" }}\n\
             material = {{ type = \"translucent\", preset = \"marble\", mm_per_unit = 10.0 }}\n\n\
             [[light]]\ntype = \"directional\"\ndirection = [0.0, 1.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]\n\n\
             [render]\ngather = \"texture\"\n"
        );
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, scene).unwrap();
        let out = subcommand("plan", &[path.to_str().unwrap(), "--json"]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let atlas = &json["atlases"][0];
        assert_eq!(atlas["source"], source, "{name}: {atlas}");
        assert_eq!(atlas["why"], why, "{name}: {atlas}");
        assert_eq!(atlas["resolution"], 256);
    }
}

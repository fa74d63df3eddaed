//! glTF 2.0 meshes (issue 48, part 3): the same mesh as OBJ and as glTF loads as the same bits
//! and renders the same image, nodes place their meshes, and bad files are refused naming the
//! file and what in it is wrong.

mod common;

use common::{repo_path, temp_dir, text, translucent};
use glam::Vec3;
use translucent::mesh::{GltfProblem, LoadOptions, Mesh, MeshError, glb_bytes};

/// Positions of a unit right triangle and its indices, as a glTF binary chunk, with the JSON
/// of accessors 0 (positions) and 1 (indices) over it.
fn triangle_bin() -> (Vec<u8>, &'static str) {
    let positions = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    bin.extend([0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    let views = r#""buffers": [{"byteLength": 48}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}
        ]"#;
    (bin, views)
}

fn parse(json: &str, bin: &[u8]) -> Result<Mesh, MeshError> {
    Mesh::from_gltf_slice(&glb_bytes(json.as_bytes(), bin), "test.glb", None, &LoadOptions::default())
}

fn problem(result: Result<Mesh, MeshError>) -> (String, GltfProblem) {
    match result {
        Err(e @ MeshError::Gltf { .. }) => {
            let message = e.to_string();
            let MeshError::Gltf { problem, .. } = e else { unreachable!() };
            (message, *problem)
        }
        other => panic!("not a glTF error: {other:?}"),
    }
}

#[test]
fn the_same_mesh_as_obj_and_as_glb_loads_as_the_same_bits() {
    let obj = Mesh::load(repo_path("assets/bunny-1.8k.obj"), &LoadOptions::default()).unwrap();
    let glb = Mesh::load(repo_path("assets/bunny-1.8k.glb"), &LoadOptions::default()).unwrap();
    assert_eq!(glb.positions().len(), 1839);
    let bits = |m: &Mesh| m.positions().iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
    assert_eq!(bits(&obj), bits(&glb));
    assert_eq!(obj.triangles(), glb.triangles());
}

/// Issue 48's target: the same mesh as OBJ and as glTF renders byte-identical images.
#[test]
fn the_same_mesh_as_obj_and_as_glb_renders_byte_identical_images() {
    let dir = temp_dir("gltf-render");
    let scene = std::fs::read_to_string(repo_path("assets/scenes/bunny-ears.toml")).unwrap();
    let assets = repo_path("assets");
    let mut pngs = Vec::new();
    for mesh in ["bunny-1.8k.obj", "bunny-1.8k.glb"] {
        let path = assets.join(mesh);
        let text_of_scene =
            scene.replace("../bunny-1.8k.obj", path.to_str().unwrap()).replace("[256, 256]", "[96, 96]");
        assert_ne!(text_of_scene, scene);
        let toml = dir.join(format!("{mesh}.toml"));
        std::fs::write(&toml, text_of_scene).unwrap();
        let png = dir.join(format!("{mesh}.png"));
        let out = translucent(&["render", toml.to_str().unwrap(), "-o", png.to_str().unwrap()], &[]);
        assert!(out.status.success(), "{mesh}: {}", text(&out.stderr));
        pngs.push(std::fs::read(&png).unwrap());
    }
    assert!(pngs[0] == pngs[1], "the OBJ and glTF renders differ");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Nodes place their meshes: a parent's translation and a child's mirroring scale compose, and
/// the mirrored triangle's winding is swapped so that it still faces out (+z for a triangle
/// counter-clockwise seen from +z, mirrored in x).
#[test]
fn nodes_place_their_meshes_and_a_mirror_keeps_the_triangles_facing_out() {
    let (bin, views) = triangle_bin();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": [{{"translation": [10, 0, 0], "children": [1]}}, {{"scale": [-1, 1, 1], "mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}], {views}}}"#
    );
    let mesh = parse(&json, &bin).unwrap();
    let mut xs: Vec<f32> = mesh.positions().iter().map(|p| p.x).collect();
    xs.sort_by(f32::total_cmp);
    assert_eq!(xs, [9.0, 10.0, 10.0]);
    let n = mesh.face_normals()[0];
    assert!(n.abs_diff_eq(Vec3::Z, 1e-6), "{n}");
}

#[test]
fn a_bad_glb_is_refused_naming_the_file_and_what_in_it_is_wrong() {
    let (bin, views) = triangle_bin();
    let with = |primitive: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
            "meshes": [{{"primitives": [{primitive}]}}], {views}}}"#
        )
    };
    // Points, not triangles.
    let (message, p) = problem(parse(&with(r#"{"attributes": {"POSITION": 0}, "mode": 0}"#), &bin));
    assert!(matches!(p, GltfProblem::NotTriangles { node: 0, mesh: 0, primitive: 0, .. }), "{p:?}");
    assert!(message.starts_with("test.glb: ") && message.contains("primitive 0"), "{message}");
    // An index past the vertices.
    let mut past = bin.clone();
    past[44..48].copy_from_slice(&7u32.to_le_bytes());
    let (message, p) = problem(parse(&with(r#"{"attributes": {"POSITION": 0}, "indices": 1}"#), &past));
    assert!(matches!(p, GltfProblem::BadIndices { accessor: 1, .. }), "{p:?}");
    assert!(message.contains("accessor 1 refers to vertex 7, but the primitive has 3"), "{message}");
    // A binary chunk shorter than its buffer.
    let (_, p) = problem(parse(&with(r#"{"attributes": {"POSITION": 0}}"#), &bin[..40]));
    assert!(matches!(p, GltfProblem::ShortBuffer { .. } | GltfProblem::Parse(_)), "{p:?}");
    // POSITION naming an accessor that is not there (the gltf crate's validation panicked on it;
    // fuzz/corpus/gltf/regression-position-accessor-missing.glb).
    let (message, p) = problem(parse(&with(r#"{"attributes": {"POSITION": 5}}"#), &bin));
    assert!(matches!(p, GltfProblem::NoSuchAccessor { accessor: 5, count: 2, .. }), "{p:?}");
    assert!(message.contains("POSITION is accessor 5, and the file has 2 accessors"), "{message}");
    // A GLB header whose length is under 12 (the gltf crate subtracted unchecked).
    let mut short = glb_bytes(with(r#"{"attributes": {"POSITION": 0}}"#).as_bytes(), &bin);
    short[8..12].copy_from_slice(&0u32.to_le_bytes());
    let (_, p) = problem(Mesh::from_gltf_slice(&short, "short.glb", None, &LoadOptions::default()));
    assert!(matches!(p, GltfProblem::GlbLength { declared: 0 }), "{p:?}");
    // POSITION as two floats, not three (the reader asserted on it in debug builds).
    let (_, p) = problem(parse(&with(r#"{"attributes": {"POSITION": 1}}"#), &bin));
    assert!(matches!(p, GltfProblem::Accessor { accessor: 1, role: "POSITION", .. } | GltfProblem::Parse(_)), "{p:?}");
    // An accessor of no element (the reader subtracted one from its count unchecked).
    let empty = with(r#"{"attributes": {"POSITION": 0}, "indices": 1}"#).replace(r#""count": 3, "type": "SCALAR""#, r#""count": 0, "type": "SCALAR""#);
    let (message, p) = problem(parse(&empty, &bin));
    assert!(matches!(p, GltfProblem::Accessor { accessor: 1, role: "indices", .. }), "{p:?}");
    assert!(message.contains("holds 0 elements"), "{message}");
    for regression in [
        "regression-position-vec2.glb",
        "regression-glb-length-zero.glb",
        "regression-accessor-count-zero.glb",
        "regression-position-accessor-missing.glb",
    ] {
        let fuzzed = std::fs::read(repo_path(&format!("fuzz/corpus/gltf/{regression}"))).unwrap();
        assert!(Mesh::from_gltf_slice(&fuzzed, regression, None, &LoadOptions::default()).is_err(), "{regression}");
    }
    // Nodes that are not trees: a cycle (it recursed without end), and two parents.
    let graph = |nodes: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}], "nodes": {nodes},
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}], {views}}}"#
        )
    };
    let (message, p) = problem(parse(&graph(r#"[{"mesh": 0}, {"children": [2]}, {"children": [1]}]"#), &bin));
    assert!(matches!(p, GltfProblem::NotATree { why: "is its own ancestor", .. }), "{p:?}");
    assert!(message.contains("glTF nodes must form trees"), "{message}");
    let (_, p) = problem(parse(&graph(r#"[{"children": [1, 2]}, {"children": [2]}, {"mesh": 0}]"#), &bin));
    assert!(matches!(p, GltfProblem::NotATree { node: 2, why: "has two parents" }), "{p:?}");
    // A buffer as a data: URI.
    let data = r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 4, "uri": "data:application/octet-stream;base64,AAAAAA=="}]}"#;
    let (_, p) = problem(parse(data, &[]));
    assert!(matches!(p, GltfProblem::DataUri { buffer: 0 }), "{p:?}");
    // Not glTF at all, and a scene with no mesh.
    let (message, p) = problem(Mesh::from_gltf_slice(b"glTF\x02\0\0\0", "cut.glb", None, &LoadOptions::default()));
    assert!(matches!(p, GltfProblem::Parse(_)) && message.starts_with("cut.glb: "), "{message}");
    let (_, p) = problem(parse(r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": []}]}"#, &[]));
    assert!(matches!(p, GltfProblem::NoMesh), "{p:?}");
}

/// Through the command line: a `.gltf` whose buffer file is missing stops the render with the
/// scene's mesh file and the buffer named, a non-zero exit, and no image written; with the file
/// there, it renders.
#[test]
fn a_gltf_with_a_missing_buffer_file_stops_the_render_naming_it() {
    let dir = temp_dir("gltf-missing-bin");
    let (_, views) = triangle_bin();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}], {}}}"#,
        views.replace(r#""byteLength": 48}"#, r#""byteLength": 48, "uri": "gone.bin"}"#)
    );
    std::fs::write(dir.join("tri.gltf"), json).unwrap();
    let scene = "[camera]\neye = [0.5, 0.5, 3.0]\ntarget = [0.3, 0.3, 0.0]\nfov_y = 30.0\nresolution = [32, 32]\n\
                 [[object]]\nshape = { type = \"mesh\", path = \"tri.gltf\" }\n\
                 material = { type = \"translucent\", preset = \"marble\", mm_per_unit = 10.0 }\n\
                 [[light]]\ntype = \"directional\"\ndirection = [0.0, 0.0, 1.0]\nirradiance = [1.0, 1.0, 1.0]\n";
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let png = dir.join("out.png");
    let out = translucent(&["render", dir.join("scene.toml").to_str().unwrap(), "-o", png.to_str().unwrap()], &[]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(stderr.contains("tri.gltf") && stderr.contains("buffer 0") && stderr.contains("gone.bin"), "{stderr}");
    assert!(!png.exists());
    // With its buffer file there, the same scene renders.
    std::fs::write(dir.join("gone.bin"), triangle_bin().0).unwrap();
    let out = translucent(&["render", dir.join("scene.toml").to_str().unwrap(), "-o", png.to_str().unwrap()], &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(png.is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene's object can take one named node of a glTF file (with its children), placed as the
/// file's scene places it; a name that no node has is refused listing the names there are, and
/// `node` on an OBJ mesh is refused naming the key.
#[test]
fn an_object_takes_one_named_node_of_a_gltf_placed_as_its_scene_places_it() {
    let dir = temp_dir("gltf-node");
    let (bin, views) = triangle_bin();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0, 1]}}],
        "nodes": [{{"name": "Left", "translation": [-5, 0, 0], "mesh": 0}},
                  {{"name": "Group", "translation": [5, 0, 0], "children": [2]}},
                  {{"name": "Right", "translation": [0, 3, 0], "mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}], {views}}}"#
    );
    let file = dir.join("two.glb");
    std::fs::write(&file, glb_bytes(json.as_bytes(), &bin)).unwrap();
    let min = |m: &Mesh| m.positions().iter().fold(Vec3::INFINITY, |a, p| a.min(*p));
    let right = Mesh::load_gltf_node(&file, "Right", &LoadOptions::default()).unwrap();
    assert_eq!((right.positions().len(), min(&right)), (3, Vec3::new(5.0, 3.0, 0.0)));
    let left = Mesh::load_gltf_node(&file, "Left", &LoadOptions::default()).unwrap();
    assert_eq!(min(&left), Vec3::new(-5.0, 0.0, 0.0));
    let whole = Mesh::load(&file, &LoadOptions::default()).unwrap();
    assert_eq!(whole.positions().len(), 6);
    let (message, p) = problem(Mesh::load_gltf_node(&file, "Middle", &LoadOptions::default()));
    assert!(matches!(&p, GltfProblem::NoSuchNode { names, .. } if names == &["Left", "Group", "Right"]), "{p:?}");
    assert!(message.contains("two.glb") && message.contains("\"Middle\""), "{message}");

    let scene = |path: &str| {
        format!(
            "[camera]\neye = [0.0, 0.0, 30.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40.0\nresolution = [32, 32]\n\
             [[object]]\nshape = {{ type = \"mesh\", path = \"{path}\", node = \"Right\" }}\n\
             material = {{ type = \"translucent\", preset = \"marble\", mm_per_unit = 10.0 }}\n\
             [[light]]\ntype = \"directional\"\ndirection = [0.0, 0.0, 1.0]\nirradiance = [1.0, 1.0, 1.0]\n"
        )
    };
    let prepared = |text: &str| {
        let scene = translucent::scene::Scene::parse(text, "node.toml", Some(dir.clone()))?;
        translucent::scene::build::PreparedScene::new(&scene, &Default::default()).map(|p| p.objects[0].mesh.positions().len())
    };
    assert_eq!(prepared(&scene("two.glb")).unwrap(), 3);
    let refused = prepared(&scene("../bunny.obj")).unwrap_err().to_string();
    assert!(refused.contains("shape.node") && refused.contains("not a .gltf or .glb"), "{refused}");
    let _ = std::fs::remove_dir_all(&dir);
}

//! Write a mesh as a binary glTF 2.0 file, as this project reads it: `cargo run --release --example
//! obj_to_glb -- IN.obj OUT.glb`. The positions and triangles are those `Mesh::load` makes of the
//! OBJ (f32, welded), in one buffer, one mesh, one node and one scene, so that the glTF loads as
//! the same mesh bit for bit (`tests/gltf.rs`). How `assets/bunny-1.8k.glb` was made.
use translucent::mesh::{LoadOptions, Mesh};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, input, output] = &args[..] else {
        eprintln!("usage: obj_to_glb IN.obj OUT.glb");
        std::process::exit(2);
    };
    let mesh = Mesh::load(input, &LoadOptions::default()).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1);
    });
    std::fs::write(output, glb(mesh.positions(), mesh.triangles())).unwrap_or_else(|e| {
        eprintln!("{output}: {e}");
        std::process::exit(1);
    });
    eprintln!("wrote {output}: {} vertices, {} triangles", mesh.positions().len(), mesh.triangles().len());
}

/// A `.glb` of one mesh: its positions, then its indices, in the binary chunk.
fn glb(positions: &[glam::Vec3], triangles: &[[u32; 3]]) -> Vec<u8> {
    let mut bin: Vec<u8> = positions.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes).collect();
    let index_offset = bin.len();
    bin.extend(triangles.iter().flatten().flat_map(|i| i.to_le_bytes()));
    let (lo, hi) =
        positions.iter().fold((glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let json = serde_json::json!({
        "asset": { "version": "2.0", "generator": "translucent examples/obj_to_glb.rs" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "mode": 4 }] }],
        "buffers": [{ "byteLength": bin.len() }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": index_offset, "target": 34962 },
            { "buffer": 0, "byteOffset": index_offset, "byteLength": bin.len() - index_offset, "target": 34963 },
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3",
              "min": lo.to_array(), "max": hi.to_array() },
            { "bufferView": 1, "componentType": 5125, "count": triangles.len() * 3, "type": "SCALAR" },
        ],
    });
    translucent::mesh::glb_bytes(&serde_json::to_vec(&json).expect("JSON"), &bin)
}

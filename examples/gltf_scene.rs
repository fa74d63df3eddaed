//! Write the glTF scene test asset: `cargo run --release --example gltf_scene -- assets/bunny-1.8k.obj
//! assets/scenes/bunny-volume.glb`. The 1.8k-vertex bunny (as `Mesh::load` makes it of the OBJ)
//! placed by its node 5 cm long, its lowest point at y = 0; a perspective camera; a
//! `KHR_lights_punctual` point light behind it and a directional fill from the front; and a
//! `KHR_materials_volume` material with `KHR_materials_ior`. The camera and lights sit at
//! dyadic positions with no rotation, and the lights' intensities are multiples of 683/64, so
//! that a TOML scene can state the same camera and lights exactly (`tests/gltf_scene.rs`).
use glam::Vec3;
use translucent::mesh::{LoadOptions, Mesh};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, input, output] = &args[..] else {
        eprintln!("usage: gltf_scene IN.obj OUT.glb");
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

/// The node's scale and translation: the mesh 5 cm along its longest side, centred on the y
/// axis with its lowest point at y = 0 (as a scene's `transform = { fit = 0.05 }`).
fn fit(lo: Vec3, hi: Vec3) -> (f32, Vec3) {
    let scale = 0.05 / (hi - lo).max_element();
    let centre = Vec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
    (scale, -centre * scale)
}

/// The scene as a `.glb`: the mesh's positions, then its indices, in the binary chunk.
fn glb(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<u8> {
    let mut bin: Vec<u8> = positions.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes).collect();
    let index_offset = bin.len();
    bin.extend(triangles.iter().flatten().flat_map(|i| i.to_le_bytes()));
    let (lo, hi) = positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let (scale, translation) = fit(lo, hi);
    let json = serde_json::json!({
        "asset": { "version": "2.0", "generator": "translucent examples/gltf_scene.rs" },
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_volume", "KHR_materials_ior"],
        "extensions": { "KHR_lights_punctual": { "lights": [
            { "name": "back", "type": "point", "color": [1.0, 0.875, 0.75], "intensity": 683.0 / 64.0 },
            { "name": "fill", "type": "directional", "color": [1.0, 1.0, 1.0], "intensity": 683.0 / 2.0 },
        ] } },
        "scene": 0,
        "scenes": [{ "nodes": [0, 1, 2, 3] }],
        "nodes": [
            { "name": "bunny", "mesh": 0, "scale": [scale, scale, scale], "translation": translation.to_array() },
            { "name": "camera", "camera": 0, "translation": [0.0, 0.0234375, 0.15625] },
            { "name": "back", "translation": [0.03125, 0.0625, -0.0625],
              "extensions": { "KHR_lights_punctual": { "light": 0 } } },
            { "name": "fill", "extensions": { "KHR_lights_punctual": { "light": 1 } } },
        ],
        "cameras": [{ "type": "perspective", "perspective": { "yfov": 30f32.to_radians(), "znear": 0.01 } }],
        "materials": [{
            "name": "stone",
            "pbrMetallicRoughness": { "baseColorFactor": [0.83, 0.79, 0.75, 1.0], "metallicFactor": 0.0,
                                      "roughnessFactor": 0.35 },
            "extensions": {
                "KHR_materials_volume": { "thicknessFactor": 0.01, "attenuationDistance": 0.001,
                                          "attenuationColor": [0.112, 0.0728, 0.0498] },
                "KHR_materials_ior": { "ior": 1.3 },
            },
        }],
        "meshes": [{ "name": "bunny", "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "material": 0 }] }],
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

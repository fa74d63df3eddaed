//! The glTF reader: the gltf crate's parsing and validation, our buffers, nodes and accessors,
//! and the mesh pipeline behind `Mesh::from_gltf_slice`. Whatever it accepts must come out
//! finite; whatever it refuses must be an error, never a panic. (No base folder: a `.gltf`'s
//! buffer files are never opened.)
#![no_main]

use libfuzzer_sys::fuzz_target;
use translucent::mesh::{LoadOptions, Mesh};

fuzz_target!(|data: &[u8]| {
    let Ok(mesh) = Mesh::from_gltf_slice(data, "fuzz.glb", None, &LoadOptions::default()) else { return };
    assert!(!mesh.triangles().is_empty());
    assert!(mesh.positions().iter().all(|p| p.is_finite()), "non-finite position");
    assert!(mesh.face_normals().iter().all(|n| n.is_finite()), "non-finite face normal");
    assert!(mesh.vertex_normals().iter().all(|n| n.is_finite()), "non-finite vertex normal");
    assert!(mesh.triangle_areas().iter().all(|a| a.is_finite() && *a > 0.0), "bad triangle area");
    let n = mesh.positions().len();
    assert!(mesh.triangles().iter().flatten().all(|&i| (i as usize) < n));
});

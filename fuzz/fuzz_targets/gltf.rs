//! The glTF reader: the gltf crate's parsing and validation, our buffers, nodes and accessors,
//! and the mesh pipeline behind `Mesh::from_gltf_slice`; then the same bytes as a scene
//! (`Scene::from_gltf_slice`: cameras, lights, materials, the scene checks). Whatever they
//! accept must come out finite; whatever they refuse must be an error, never a panic. (No base
//! folder for the mesh, one that does not exist for the scene: a `.gltf`'s buffer files are
//! never read.)
#![no_main]

use libfuzzer_sys::fuzz_target;
use translucent::mesh::{LoadOptions, Mesh};
use translucent::scene::{GltfOverrides, Scene};

fuzz_target!(|data: &[u8]| {
    let base = std::path::PathBuf::from("/nonexistent-fuzz-base");
    if let Ok(scene) = Scene::from_gltf_slice(data, "fuzz.glb", (base, "fuzz.glb"), &GltfOverrides::default()) {
        assert!(!scene.file.objects.is_empty());
        let c = &scene.file.camera;
        assert!(c.eye.iter().chain(&c.target).all(|v| v.is_finite()), "non-finite camera");
    }
    let Ok(mesh) = Mesh::from_gltf_slice(data, "fuzz.glb", None, &LoadOptions::default()) else { return };
    assert!(!mesh.triangles().is_empty());
    assert!(mesh.positions().iter().all(|p| p.is_finite()), "non-finite position");
    assert!(mesh.face_normals().iter().all(|n| n.is_finite()), "non-finite face normal");
    assert!(mesh.vertex_normals().iter().all(|n| n.is_finite()), "non-finite vertex normal");
    assert!(mesh.triangle_areas().iter().all(|a| a.is_finite() && *a > 0.0), "bad triangle area");
    let n = mesh.positions().len();
    assert!(mesh.triangles().iter().flatten().all(|&i| (i as usize) < n));
});

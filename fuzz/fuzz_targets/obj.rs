//! The OBJ reader: the line-numbering pre-scan, tobj, and the mesh pipeline behind
//! `Mesh::from_obj_text` (weld, degenerate triangles, topology, curvature). Whatever it accepts
//! must come out finite; whatever it refuses must be an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use translucent::mesh::{LoadOptions, Mesh};

fuzz_target!(|data: &[u8]| {
    // The file loader reads bytes lossily as UTF-8 too (`Mesh::load`).
    let text = String::from_utf8_lossy(data);
    let Ok(mesh) = Mesh::from_obj_text(&text, "fuzz.obj", &LoadOptions::default()) else { return };
    assert!(!mesh.triangles().is_empty());
    assert!(mesh.positions().iter().all(|p| p.is_finite()), "non-finite position");
    assert!(mesh.face_normals().iter().all(|n| n.is_finite()), "non-finite face normal");
    assert!(mesh.vertex_normals().iter().all(|n| n.is_finite()), "non-finite vertex normal");
    assert!(mesh.triangle_areas().iter().all(|a| a.is_finite() && *a > 0.0), "bad triangle area");
    assert!(mesh.total_area().is_finite(), "non-finite total area");
    let n = mesh.positions().len();
    assert!(mesh.triangles().iter().flatten().all(|&i| (i as usize) < n));
});

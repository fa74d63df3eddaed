//! What of glTF needs no glTF reader, and so is built without the `gltf` feature: the GLB
//! container's layout (the examples write assets with it) and the name of one node's part of a
//! file's scene.

/// The triangle primitives of one node of a glTF file's scene that share one material, placed as
/// the scene places the node (its children not included): what one object of a glTF scene is
/// (`scene::Scene::from_gltf`), so that each part of a node gets its own material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GltfNodePart {
    /// The node's index in the file.
    pub node: usize,
    /// The material's index of the primitives taken (`None`: those with the default material).
    pub material: Option<usize>,
}

/// A binary glTF (`.glb`) holding `json` and the binary chunk `bin`, each padded to 4 bytes as
/// the container asks (JSON with spaces, binary with zeros).
pub fn glb_bytes(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |n: usize| n.div_ceil(4) * 4;
    let (json_len, bin_len) = (pad(json.len()), pad(bin.len()));
    let total = 12 + 8 + json_len + if bin.is_empty() { 0 } else { 8 + bin_len };
    let mut out = Vec::with_capacity(total);
    for word in [0x4654_6C67u32, 2, total as u32, json_len as u32, 0x4E4F_534A] {
        out.extend(word.to_le_bytes());
    }
    out.extend(json);
    out.resize(20 + json_len, b' ');
    if !bin.is_empty() {
        for word in [bin_len as u32, 0x004E_4942] {
            out.extend(word.to_le_bytes());
        }
        out.extend(bin);
        out.resize(total, 0);
    }
    out
}

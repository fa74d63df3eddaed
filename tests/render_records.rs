//! The std430 records shared by the render passes: Rust mirrors (`#[repr(C)]` + bytemuck) must
//! have the sizes and offsets that std430 gives the GLSL declarations, read from the GLSL
//! headers themselves so a field added on one side only fails here.

use std::mem::{offset_of, size_of};
use translucent::render::records::{ObjectRecord, SampleRecord, Vertex};
use translucent::render::shade::ShadePush;
use translucent::scene::lights::LightGpu;

/// (field name, std430 offset) of `struct NAME { ... };` in `source`, for the member types used
/// here (all 16-byte aligned: vec4, uvec4, mat4 and arrays of them).
fn glsl_layout(source: &str, name: &str) -> (Vec<(String, usize)>, usize) {
    let start = source.find(&format!("struct {name} {{")).unwrap_or_else(|| panic!("struct {name} not found"));
    let body = &source[start..source[start..].find("};").unwrap() + start];
    let mut offset = 0;
    let mut fields = Vec::new();
    for line in body.lines().skip(1) {
        let code = line.split("//").next().unwrap().trim();
        if code.is_empty() {
            continue;
        }
        let code = code.trim_end_matches(';');
        let mut parts = code.split_whitespace();
        let ty = parts.next().unwrap();
        let decl = parts.next().unwrap();
        let (field, count) = match decl.split_once('[') {
            Some((f, n)) => (f.to_string(), n.trim_end_matches(']').parse::<usize>().unwrap()),
            None => (decl.to_string(), 1),
        };
        let size = match ty {
            "vec4" | "uvec4" => 16,
            "mat4" => 64,
            other => panic!("type {other} of {name}.{field} is not handled here"),
        };
        fields.push((field, offset));
        offset += size * count;
    }
    (fields, offset)
}

#[test]
fn scene_records_match_glsl() {
    let scene = include_str!("../glsl/common/scene.glsl");
    let (fields, size) = glsl_layout(scene, "ObjectRecord");
    assert_eq!(size, size_of::<ObjectRecord>());
    let rust = [
        ("albedo_roughness", offset_of!(ObjectRecord, albedo_roughness)),
        ("eta_norm_kind", offset_of!(ObjectRecord, eta_norm_kind)),
        ("dipole", offset_of!(ObjectRecord, dipole)),
        ("ranges", offset_of!(ObjectRecord, ranges)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));

    let (fields, size) = glsl_layout(scene, "SampleRecord");
    assert_eq!(size, size_of::<SampleRecord>());
    let rust = [
        ("position_area", offset_of!(SampleRecord, position_area)),
        ("normal_object", offset_of!(SampleRecord, normal_object)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
}

#[test]
fn light_record_matches_glsl() {
    let (fields, size) = glsl_layout(include_str!("../glsl/common/lights.glsl"), "Light");
    assert_eq!(size, size_of::<LightGpu>());
    let rust = [
        ("position_kind", offset_of!(LightGpu, position_kind)),
        ("direction_cos", offset_of!(LightGpu, direction_cos)),
        ("power_layer", offset_of!(LightGpu, power_layer)),
        ("spot_texel", offset_of!(LightGpu, spot_texel)),
        ("shadow_matrix", offset_of!(LightGpu, shadow_matrix)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
}

#[test]
fn vertex_and_push_layouts() {
    // The raster passes read `Vertex` as two vec3 attributes, and the gather as float[6].
    assert_eq!(size_of::<Vertex>(), 24);
    assert_eq!(offset_of!(Vertex, normal), 12);
    assert_eq!(Vertex::normal_attribute().offset, 12);
    // shade.vert/shade.frag: mat4 view_proj; vec4 eye_object; uvec4 counts.
    assert_eq!(size_of::<ShadePush>(), 96);
    assert_eq!(offset_of!(ShadePush, eye_object), 64);
    assert_eq!(offset_of!(ShadePush, counts), 80);
    let frag = include_str!("../glsl/common/shade.glsl");
    assert!(frag.contains("mat4 view_proj;") && frag.contains("vec4 eye_object;") && frag.contains("uvec4 counts;"));
}

//! The std430 records shared by the render passes: Rust mirrors (`#[repr(C)]` + bytemuck) must
//! have the sizes and offsets that std430 gives the GLSL declarations, read from the GLSL
//! headers themselves so a field added on one side only fails here.

use std::mem::{offset_of, size_of};
use translucent::gpu::ShaderInterface;
use translucent::render::beam_gather::BeamGatherPush;
use translucent::render::gather::GatherPush;
use translucent::render::gather_pixel::GatherPixelPush;
use translucent::render::gather_sparse::GatherSparsePush;
use translucent::render::gather_texture::GatherTexturePush;
use translucent::render::gather_tree::GatherTreePush;
use translucent::render::local_exitance::LocalExitancePush;
use translucent::render::receiver_view::ReceiverViewPush;
use translucent::render::records::{
    BeamNodeRecord, BeamReceiverRecord, BeamSourceRecord, LightGpu, NodePowerRecord, ObjectRecord, SampleRecord,
    SplatRecord, TreeNodeRecord, Vertex,
};
use translucent::render::shade::ShadePush;
use translucent::render::shadow::ShadowPush;
use translucent::render::splat::SplatPush;
use translucent::render::tonemap::TonemapPush;
use translucent::render::transport::TransportPush;
use translucent::render::vertex_light::VertexLightPush;

/// (field name, std430 offset) of `struct NAME { ... };` in `source`, for the member types used
/// here: 4-byte scalars and arrays of them, a 12-byte vec3, and 16-byte vec4, uvec4, mat4,
/// DipoleChannel and arrays of them, in an order that needs no padding (checked: every vector
/// starts on a 16-byte boundary).
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
            "float" | "uint" | "int" => 4,
            "vec3" => 12,
            "vec4" | "uvec4" | "DipoleChannel" => 16,
            "mat4" => 64,
            other => panic!("type {other} of {name}.{field} is not handled here"),
        };
        if size >= 12 {
            assert_eq!(offset % 16, 0, "{name}.{field} would need padding before it");
        }
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
        ("eta", offset_of!(ObjectRecord, eta)),
        ("norm", offset_of!(ObjectRecord, norm)),
        ("kind", offset_of!(ObjectRecord, kind)),
        ("local_channels", offset_of!(ObjectRecord, local_channels)),
        ("dipole", offset_of!(ObjectRecord, dipole)),
        ("ranges", offset_of!(ObjectRecord, ranges)),
        ("near_blend", offset_of!(ObjectRecord, near_blend)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));

    let (fields, size) = glsl_layout(scene, "SampleRecord");
    assert_eq!(size, size_of::<SampleRecord>());
    let rust = [
        ("position_area", offset_of!(SampleRecord, position_area)),
        ("normal", offset_of!(SampleRecord, normal)),
        ("face_normal", offset_of!(SampleRecord, face_normal)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
}

#[test]
fn light_record_matches_glsl() {
    let (fields, size) = glsl_layout(include_str!("../glsl/common/lights.glsl"), "Light");
    assert_eq!(size, size_of::<LightGpu>());
    let rust = [
        ("position", offset_of!(LightGpu, position)),
        ("kind", offset_of!(LightGpu, kind)),
        ("direction_cos", offset_of!(LightGpu, direction_cos)),
        ("power_layer", offset_of!(LightGpu, power_layer)),
        ("spot_texel", offset_of!(LightGpu, spot_texel)),
        ("shadow_matrix", offset_of!(LightGpu, shadow_matrix)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
}

#[test]
fn vertex_and_push_layouts() {
    // The raster passes read `Vertex` as two vec3 attributes, compute passes as `VertexRecord`.
    assert_eq!(size_of::<Vertex>(), 24);
    assert_eq!(offset_of!(Vertex, normal), 12);
    assert_eq!(Vertex::normal_attribute().offset, 12);
    // shade.vert/shade.frag: mat4 view_proj; vec4 eye_object; uvec4 counts; vec4
    // albedo_roughness; vec4 material: 128 bytes, the least maxPushConstantsSize Vulkan allows.
    assert_eq!(size_of::<ShadePush>(), 128);
    assert_eq!(offset_of!(ShadePush, eye_object), 64);
    assert_eq!(offset_of!(ShadePush, counts), 80);
    assert_eq!(offset_of!(ShadePush, albedo_roughness), 96);
    assert_eq!(offset_of!(ShadePush, material), 112);
    let frag = include_str!("../glsl/common/shade_push.glsl");
    assert!(frag.contains("mat4 view_proj;") && frag.contains("vec4 eye_object;") && frag.contains("uvec4 counts;"));
}

#[test]
fn splat_and_vertex_records_match_glsl() {
    let scene = include_str!("../glsl/common/scene.glsl");
    let (fields, size) = glsl_layout(scene, "SplatRecord");
    assert_eq!(size, size_of::<SplatRecord>());
    let rust = [
        ("irradiance_area", offset_of!(SplatRecord, irradiance_area)),
        ("near_energy", offset_of!(SplatRecord, near_energy)),
        ("beam", offset_of!(SplatRecord, beam)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
    let (fields, size) = glsl_layout(scene, "TreeNodeRecord");
    assert_eq!(size, size_of::<TreeNodeRecord>());
    let rust = [
        ("center_radius", offset_of!(TreeNodeRecord, center_radius)),
        ("area_reach", offset_of!(TreeNodeRecord, area_reach)),
        ("range_skip", offset_of!(TreeNodeRecord, range_skip)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
    let (fields, size) = glsl_layout(scene, "NodePowerRecord");
    assert_eq!(size, size_of::<NodePowerRecord>());
    let rust = [
        ("power", offset_of!(NodePowerRecord, power)),
        ("mean_weight", offset_of!(NodePowerRecord, mean_weight)),
        ("cov_diag", offset_of!(NodePowerRecord, cov_diag)),
        ("cov_off", offset_of!(NodePowerRecord, cov_off)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
    let (fields, size) = glsl_layout(scene, "BeamNodeRecord");
    assert_eq!(size, size_of::<BeamNodeRecord>());
    let rust = [
        ("power", offset_of!(BeamNodeRecord, power)),
        ("position", offset_of!(BeamNodeRecord, position)),
        ("normal", offset_of!(BeamNodeRecord, normal)),
        ("beam", offset_of!(BeamNodeRecord, beam)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
    let (fields, size) = glsl_layout(scene, "BeamSourceRecord");
    assert_eq!(size, size_of::<BeamSourceRecord>());
    let rust = [
        ("position_mu", offset_of!(BeamSourceRecord, position_mu)),
        ("power_area", offset_of!(BeamSourceRecord, power_area)),
        ("normal_along", offset_of!(BeamSourceRecord, normal_along)),
    ];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
    let (fields, size) = glsl_layout(scene, "BeamReceiverRecord");
    assert_eq!(size, size_of::<BeamReceiverRecord>());
    let rust =
        [("norm", offset_of!(BeamReceiverRecord, norm)), ("first_item", offset_of!(BeamReceiverRecord, first_item))];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
    let (fields, size) = glsl_layout(scene, "VertexRecord");
    assert_eq!(size, size_of::<Vertex>());
    let rust = [("position", offset_of!(Vertex, position)), ("normal", offset_of!(Vertex, normal))];
    assert_eq!(fields, rust.map(|(n, o)| (n.to_string(), o)));
}

/// Every pass's push struct: its GLSL declaration has the Rust struct's field names and
/// offsets, and the compiled shader's reflected push block has its size.
/// One pass's push block: shader, GLSL source holding the struct, struct name, Rust size, fields.
type PushCase = (&'static str, &'static str, &'static str, usize, &'static [&'static str]);

/// Every pass's push block, as `push_blocks_match_glsl_and_spirv` checks them.
/// `GatherTexturePush`'s fields, in order.
/// The two-stage gathers' push block (`GroupGatherPush`), the same in both shaders.
const GROUP_GATHER_PUSH_FIELDS: [&str; 10] = [
    "object",
    "stage",
    "first_node",
    "node_count",
    "first_receiver",
    "first_group",
    "receiver_count",
    "first_listed",
    "listed_count",
    "only_picked",
];

const TEXTURE_PUSH_FIELDS: [&str; 12] = [
    "object",
    "stage",
    "depth",
    "levels",
    "first_node",
    "first_index",
    "resolution",
    "samples",
    "radius",
    "seed",
    "first_entry",
    "receiver_count",
];

/// `SplatPush`'s fields, in order.
const SPLAT_PUSH_FIELDS: [&str; 8] = [
    "object",
    "first_sample",
    "sample_count",
    "light_count",
    "key_light_count",
    "environment_kept",
    "caster_triangles",
    "ray_offset",
];

fn push_cases() -> [PushCase; 12] {
    [
        (
            "beam_gather.comp",
            include_str!("../glsl/beam_gather.comp"),
            "BeamGatherPush",
            size_of::<BeamGatherPush>(),
            &["object", "tree", "critical", "normal_total", "stage"],
        ),
        ("splat.comp", include_str!("../glsl/splat.comp"), "SplatPush", size_of::<SplatPush>(), &SPLAT_PUSH_FIELDS),
        (
            "local_exitance.comp",
            include_str!("../glsl/local_exitance.comp"),
            "LocalExitancePush",
            size_of::<LocalExitancePush>(),
            &["first_vertex", "vertex_count", "object", "key_light_count", "shadow_radius"],
        ),
        (
            "vertex_light.comp",
            include_str!("../glsl/vertex_light.comp"),
            "VertexLightPush",
            size_of::<VertexLightPush>(),
            &["first_vertex", "vertex_count", "light_count", "eta"],
        ),
        (
            "gather.comp",
            include_str!("../glsl/gather.comp"),
            "GatherPush",
            size_of::<GatherPush>(),
            &["object", "first_node", "node_count", "first_entry", "receiver_count"],
        ),
        (
            "gather_sparse.comp",
            include_str!("../glsl/gather_sparse.comp"),
            "GatherSparsePush",
            size_of::<GatherSparsePush>(),
            &GROUP_GATHER_PUSH_FIELDS,
        ),
        (
            "gather_tree.comp",
            include_str!("../glsl/gather_tree.comp"),
            "GatherTreePush",
            size_of::<GatherTreePush>(),
            &GROUP_GATHER_PUSH_FIELDS,
        ),
        (
            "gather_texture.comp",
            include_str!("../glsl/gather_texture.comp"),
            "GatherTexturePush",
            size_of::<GatherTexturePush>(),
            &TEXTURE_PUSH_FIELDS,
        ),
        (
            "gather_pixel.comp",
            include_str!("../glsl/gather_pixel.comp"),
            "GatherPixelPush",
            size_of::<GatherPixelPush>(),
            &["width", "height"],
        ),
        (
            "tonemap.comp",
            include_str!("../glsl/tonemap.comp"),
            "TonemapPush",
            size_of::<TonemapPush>(),
            &["width", "height", "exposure"],
        ),
        (
            "shadow.vert",
            include_str!("../glsl/shadow.vert"),
            "ShadowPush",
            size_of::<ShadowPush>(),
            &["light_matrix", "layer"],
        ),
        (
            "shade.vert",
            include_str!("../glsl/common/shade_push.glsl"),
            "ShadePush",
            size_of::<ShadePush>(),
            &["view_proj", "eye_object", "counts", "albedo_roughness", "material"],
        ),
    ]
}

/// The push blocks of the steps inside a pass (the hierarchical gather's pick of receivers),
/// and of the passes that follow the gather (`push_cases` holds the rest: one list would pass
/// a screen).
fn step_push_cases() -> [PushCase; 2] {
    [
        (
            "receiver_view.comp",
            include_str!("../glsl/receiver_view.comp"),
            "ReceiverViewPush",
            size_of::<ReceiverViewPush>(),
            &[
                "view_proj",
                "eye",
                "first_receiver",
                "receiver_count",
                "generation",
                "flags",
                "sweep",
                "reach",
                "stage",
                "kernel",
            ],
        ),
        (
            "transport.comp",
            include_str!("../glsl/transport.comp"),
            "TransportPush",
            size_of::<TransportPush>(),
            &["stage", "vertices", "frame"],
        ),
    ]
}

#[test]
fn push_blocks_match_glsl_and_spirv() {
    for (shader, source, name, rust_size, rust_fields) in push_cases().into_iter().chain(step_push_cases()) {
        let (fields, size) = glsl_layout(source, name);
        assert_eq!(size, rust_size, "{name}: GLSL and Rust sizes differ");
        let names: Vec<&str> = fields.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, rust_fields, "{name}: fields differ");
        let reflected = ShaderInterface::of(shader).unwrap();
        assert_eq!(reflected.push_bytes as usize, rust_size, "{shader}: reflected push block");
    }
    // Offsets of the multi-field structs, against repr(C).
    assert_eq!(offset_of!(SplatPush, light_count), 12);
    assert_eq!(offset_of!(SplatPush, environment_kept), 20);
    assert_eq!(offset_of!(SplatPush, ray_offset), 28);
    assert_eq!(offset_of!(LocalExitancePush, shadow_radius), 16);
    assert_eq!(offset_of!(VertexLightPush, eta), 12);
    assert_eq!(offset_of!(TonemapPush, exposure), 8);
    assert_eq!(offset_of!(ShadowPush, layer), 64);
}

// Scene records (std430) shared by the splat, gather and shade passes, mirrored in Rust by
// `src/render/records.rs` (a test pins sizes and offsets).
#ifndef SCENE_GLSL
#define SCENE_GLSL

const uint MATERIAL_OPAQUE = 0u;
const uint MATERIAL_TRANSLUCENT = 1u;

struct ObjectRecord {
    vec4 albedo_roughness;  // opaque: rgb albedo; w: GGX roughness (both kinds)
    vec4 eta_norm_kind;     // x: relative index of refraction eta; y: BSSRDF normalization
                            // 1 / (pi T(eta)), T(eta) = 1 - 2 FM1(eta) (optics::Dipole::s_d);
                            // z: kind (MATERIAL_*); w: unused
    vec4 dipole[3];         // per channel: alpha', sigma_tr, z_r, z_v in scene units
    uvec4 ranges;           // x: first vertex, y: vertex count, z: first sample, w: sample count
};

struct SampleRecord {
    vec4 position_area;     // xyz: world position; w: area weight (scene units^2)
    vec4 normal_object;     // xyz: unit normal; w: object index (as float)
};

#endif

#version 450
// Dipole gather (seed Eq. 11 with the near-field treatment of src/optics/kernel.rs): the radiant
// exitance at every receiver vertex of one translucent object, over that object's samples,
//     M(x) = sum_i E_i far_kernel(r_i, A_i) + sum_i phi_i E_i E_near,i / sum_i phi_i
// (kernel::far_kernel explains the split). Samples are staged through shared memory in tiles of 64 (one
// load per tile for the whole workgroup); the far sum is Kahan-compensated per channel so
// that the f32 sum stays within 1e-3 of the f64 reference at any sample count.
//
// Bindings: 0 = vertices (float[6] per vertex: position, normal; read), 1 = samples
// (SampleRecord[], read), 2 = splat (vec4[2] per sample, read), 3 = objects (ObjectRecord[], read),
// 4 = exitance (vec4 per vertex, write).
// Push: object index.
#include "dipole.glsl"
#include "scene.glsl"

#define TILE 64u
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { float vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { vec4 splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Exitance { vec4 exitance[]; };
layout(push_constant) uniform Push { uint object; } push;

shared vec4 tile_position_area[TILE];
shared vec4 tile_irradiance[TILE];
shared vec4 tile_near_energy[TILE];

void main() {
    ObjectRecord o = objects[push.object];
    uint first_vertex = o.ranges.x, vertex_count = o.ranges.y;
    uint first_sample = o.ranges.z, sample_count = o.ranges.w;
    uint local = gl_LocalInvocationID.x;
    uint v = gl_GlobalInvocationID.x;
    bool is_receiver = v < vertex_count;
    uint vi = first_vertex + min(v, max(vertex_count, 1u) - 1u);
    vec3 x = vec3(vertices[6u * vi], vertices[6u * vi + 1u], vertices[6u * vi + 2u]);
    DipoleChannel ch[3];
    for (int c = 0; c < 3; ++c) {
        vec4 d = o.dipole[c];
        ch[c] = DipoleChannel(d.x, d.y, d.z, d.w);
    }
    // Far part: sum_i E_i far_kernel(r_i, A_i), Kahan-compensated. `precise`: the
    // compensation only works if the compiler keeps the adds in this order.
    precise vec3 sum = vec3(0.0);
    precise vec3 compensation = vec3(0.0);
    // Near part: Shepard blend of the samples' near exitance E_i E_near,i (kernel::far_kernel).
    vec3 near_sum = vec3(0.0);
    float weight_sum = 0.0;
    float nearest_r = 3.4e38;
    vec3 nearest_near = vec3(0.0);
    for (uint base = 0u; base < sample_count; base += TILE) {
        uint j = base + local;
        if (j < sample_count) {
            uint s = first_sample + j;
            tile_position_area[local] = samples[s].position_area;
            tile_irradiance[local] = splat[2u * s];
            tile_near_energy[local] = splat[2u * s + 1u];
        }
        barrier();
        uint n = min(TILE, sample_count - base);
        if (is_receiver) {
            for (uint k = 0u; k < n; ++k) {
                vec4 pa = tile_position_area[k];
                float r = distance(x, pa.xyz);
                vec3 e = tile_irradiance[k].rgb;
                vec3 term;
                for (int c = 0; c < 3; ++c) {
                    term[c] = e[c] * dipole_far_kernel(ch[c], r, pa.w);
                }
                precise vec3 y = term - compensation;
                precise vec3 t = sum + y;
                compensation = (t - sum) - y;
                sum = t;
                vec3 near_exitance = e * tile_near_energy[k].rgb;
                float w = dipole_near_blend_weight(r, pa.w);
                near_sum += w * near_exitance;
                weight_sum += w;
                if (r < nearest_r) {
                    nearest_r = r;
                    nearest_near = near_exitance;
                }
            }
        }
        barrier();
    }
    vec3 near = weight_sum > 0.0 ? near_sum / weight_sum : nearest_near;
    sum += near;
    if (is_receiver) exitance[first_vertex + v] = vec4(max(sum, vec3(0.0)), 1.0);
}

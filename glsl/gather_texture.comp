#version 450
// Texture-space gather (after Chang, Lin, Ho, Huang and Chuang 2008): the samples are the
// texels of a texture atlas of the object (mesh::atlas), their transmitted irradiance E_t from
// the splat. At each receiver vertex the dipole sum of seed Eq. 11 over the texels is split in
// two (src/render/gather_texture.rs has the estimator and why it is unbiased):
//   local:  the texels of the (2h+1)^2 window around the vertex's own texel, summed exactly as
//           the vertex gather sums samples (far kernel + blended near field, glsl/common/gather.glsl);
//   global: N texels drawn in proportion to their power P_i = (E_r + E_g + E_b) A_i by descending
//           a 4-ary sum tree (a mip pyramid over the texels in Morton order), each adding
//           E_i A_i far_kernel(r_i) / (N p_i), or nothing when it lies in the window.
// The random numbers are a hash of (vertex, sample, depth, seed): fixed per receiver, so a static
// scene gives the same image every frame. reference::texture is the f64 twin; the descent is
// done in f32 there too, in the same order (`precise` here), so both draw the same texels.
//
// Stage 0 builds one depth of the sum tree (depth push.depth, 4^depth nodes, from the depth
// below or from the texels); stage 1 gathers.
//
// Bindings: 0 = vertices, 1 = samples (the texels), 2 = splat, 3 = objects, 4 = exitance (write),
// 5 = boundary distances, 6 = level vertices, 7 = texel coordinates (x | y << 16 per sample),
// 8 = texel index (per atlas texel: object-relative sample or 0xffffffff), 9 = vertex texel
// (x | y << 16 per vertex), 10 = the sum tree (float per node, written by stage 0).
// Push: GatherTexturePush.
#include "dipole.glsl"
#include "scene.glsl"
#define GATHER_TRACK_NEAREST
#include "gather.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Vertices { VertexRecord vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer Samples { SampleRecord samples[]; };
layout(std430, set = 0, binding = 2) readonly buffer Splat { SplatRecord splat[]; };
layout(std430, set = 0, binding = 3) readonly buffer Objects { ObjectRecord objects[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Exitance { vec4 exitance[]; };
layout(std430, set = 0, binding = 5) readonly buffer VertexBoundary { vec2 vertex_boundary[]; };
layout(std430, set = 0, binding = 6) readonly buffer LevelVertices { uint level_vertices[]; };
layout(std430, set = 0, binding = 7) readonly buffer TexelCoords { uint texel_coords[]; };
layout(std430, set = 0, binding = 8) readonly buffer TexelIndex { uint texel_index[]; };
layout(std430, set = 0, binding = 9) readonly buffer VertexTexel { uint vertex_texel[]; };
layout(std430, set = 0, binding = 10) buffer TexturePyramid { float pyramid[]; };
struct GatherTexturePush {
    uint object;            // the receiving object's index
    uint stage;             // 0: one depth of the sum tree; 1: the gather
    uint depth;             // stage 0: the depth built (4^depth nodes)
    uint levels;            // the tree's depth: leaves (texels) lie at this depth
    uint first_node;        // the object's root in the pyramid buffer
    uint first_index;       // its index map in texel_index
    uint resolution;        // its atlas's texels per side
    uint samples;           // importance-sampled texels per receiver (N)
    uint radius;            // the local window's half-width h, in texels
    uint seed;              // added to every hash; 0 in frames
    uint first_entry;       // its level's first entry in level_vertices
    uint receiver_count;    // the vertices its level uses
};
layout(push_constant) uniform GatherTexturePushBlock { GatherTexturePush push; };

const uint NO_TEXEL = 0xffffffffu;

// PCG hash (Jarzynski and Olano 2020, "Hash Functions for GPU Rendering").
uint pcg(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A uniform number in [0, 1) with 24 bits, exact in f32: reference::texture::random.
float random01(uint vertex, uint k, uint depth) {
    uint h = pcg(vertex + pcg(k + pcg(depth + pcg(push.seed))));
    return float(h >> 8u) * (1.0 / 16777216.0);
}

// First node of depth d: (4^d - 1) / 3.
uint depth_offset(uint d) {
    return ((1u << (2u * d)) - 1u) / 3u;
}

// Power of texel i of the object: (E_r + E_g + E_b) A, 0 past its last texel.
float leaf_power(uint i, uint first_sample, uint sample_count) {
    if (i >= sample_count) return 0.0;
    vec4 ea = splat[first_sample + i].irradiance_area;
    precise float e = (ea.r + ea.g) + ea.b;
    precise float p = e * ea.w;
    return p;
}

// Child j of node i at depth d: a node of depth d + 1, or a texel below the last depth.
float child_power(uint d, uint i, uint j, uint first_sample, uint sample_count) {
    uint c = 4u * i + j;
    if (d + 1u < push.levels) return pyramid[push.first_node + depth_offset(d + 1u) + c];
    return leaf_power(c, first_sample, sample_count);
}

// The four children's powers, written out rather than looped: llvmpipe ends any loop after
// 65,535 iterations counted over the whole invocation, and a loop over the children inside the
// depth loop inside the sample loop passed that at 4,096 samples (a silent, wrong result).
vec4 children(uint d, uint i, uint first_sample, uint sample_count) {
    return vec4(child_power(d, i, 0u, first_sample, sample_count), child_power(d, i, 1u, first_sample, sample_count),
                child_power(d, i, 2u, first_sample, sample_count), child_power(d, i, 3u, first_sample, sample_count));
}

void build(ObjectRecord o) {
    uint i = gl_GlobalInvocationID.x;
    if (i >= (1u << (2u * push.depth))) return;
    vec4 w = children(push.depth, i, o.ranges.z, o.ranges.w);
    precise float total = ((w.x + w.y) + w.z) + w.w;
    pyramid[push.first_node + depth_offset(push.depth) + i] = total;
}

// Draw one texel by power: its index (object-relative) and probability, or p = 0 when the object
// has no power.
uint draw(uint vertex, uint k, uint first_sample, uint sample_count, out float p) {
    uint node = 0u;
    p = 1.0;
    for (uint d = 0u; d < push.levels; ++d) {
        vec4 w = children(d, node, first_sample, sample_count);
        precise float total = ((w.x + w.y) + w.z) + w.w;
        if (!(total > 0.0)) {
            p = 0.0;
            return 0u;
        }
        precise float t = random01(vertex, k, d) * total;
        precise float c1 = w.x + w.y;
        precise float c2 = c1 + w.z;
        uint j = t < w.x ? 0u : (t < c1 ? 1u : (t < c2 ? 2u : 3u));
        // Rounding can land on a child without power: the last one with power before it
        // instead (written out: no loop, see children()).
        if (w[j] <= 0.0 && j == 3u) j = 2u;
        if (w[j] <= 0.0 && j == 2u) j = 1u;
        if (w[j] <= 0.0 && j == 1u) j = 0u;
        p *= w[j] / total;
        node = 4u * node + j;
    }
    return node;
}

void gather(ObjectRecord o) {
    if (gl_GlobalInvocationID.x >= push.receiver_count) return;
    uint v = level_vertices[push.first_entry + gl_GlobalInvocationID.x];
    uint vi = o.ranges.x + v;
    uint first_sample = o.ranges.z, sample_count = o.ranges.w;
    vec3 x = vertex_position(vertices[vi]);
    DipoleChannel ch[3] = gather_channels(o);
    int r = int(push.radius), side = int(push.resolution);
    ivec2 own = ivec2(vertex_texel[vi] & 0xffffu, vertex_texel[vi] >> 16u);
    GatherSum g = gather_begin();
    for (int dy = -r; dy <= r; ++dy) {
        int y = own.y + dy;
        if (y < 0 || y >= side) continue;
        for (int dx = -r; dx <= r; ++dx) {
            int tx = own.x + dx;
            if (tx < 0 || tx >= side) continue;
            uint t = texel_index[push.first_index + uint(y * side + tx)];
            if (t == NO_TEXEL) continue;
            uint s = first_sample + t;
            gather_add(g, ch, o.near_blend.rgb, x, samples[s].position_area, splat[s].irradiance_area.rgb, splat[s].near_energy.rgb);
        }
        gather_flush(g);
    }
    vec3 global = vec3(0.0);
    for (uint k = 0u; k < push.samples; ++k) {
        float p;
        uint i = draw(v, k, first_sample, sample_count, p);
        if (!(p > 0.0)) continue;
        uint c = texel_coords[first_sample + i];
        ivec2 at = ivec2(c & 0xffffu, c >> 16u);
        if (all(lessThanEqual(abs(at - own), ivec2(r)))) continue;
        vec4 pa = samples[first_sample + i].position_area;
        vec3 e = splat[first_sample + i].irradiance_area.rgb;
        vec3 d = x - pa.xyz;
        float beta = DIPOLE_B_PER_SQRT_AREA * DIPOLE_B_PER_SQRT_AREA * pa.w;
        for (int ci = 0; ci < 3; ++ci) {
            global[ci] += e[ci] * pa.w * dipole_r_d_far_sq(ch[ci], dot(d, d), beta) / p;
        }
    }
    vec3 local = gather_end(g, ch, vertex_boundary[vi]);
    vec3 m = max(local + global / float(max(push.samples, 1u)), vec3(0.0));
    exitance[vi] = vec4(m, 1.0);
}

void main() {
    ObjectRecord o = objects[push.object];
    if (push.stage == 0u) {
        build(o);
    } else {
        gather(o);
    }
}

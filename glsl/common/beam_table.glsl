// The between-points single-scattering kernel as a table: the f32 twin of
// BeamTable::lookup (src/optics/beam_table.rs, whose module doc says what is tabulated and why).
// Values at grid nodes over x = sqrt(rho / reach), cos phi in [-1, 1] and mu in [mu_c, 1], read
// trilinearly. Packed per cell for the reader (render::beam_gather::pack_tables): per channel,
// one uvec4 per cell holding its 8 corners as f16 (BeamTable rounds its values to f16, so both
// twins read the same numbers), so that a pair costs one load per channel rather than eight.
// An object's channels share the distance axis (render::beam_gather). Include after declaring
// the uvec4 array `beam_tables`.
#ifndef BEAM_TABLE_GLSL
#define BEAM_TABLE_GLSL

const uint BT_NX = 48u;
const uint BT_NY = 13u;
const uint BT_NZ = 9u;
// Cells of one channel's block.
const uint BT_CELLS = (BT_NX - 1u) * (BT_NY - 1u) * (BT_NZ - 1u);

// A grid coordinate's cell and fraction, the last cell taking the upper edge.
uint bt_cell(float x, uint n, out float f) {
    uint i = min(uint(max(floor(x), 0.0)), n - 2u);
    f = x - float(i);
    return i;
}

// Trilinear within one packed cell: x0/x1 pairs at (y0, z0), (y1, z0), (y0, z1), (y1, z1).
float bt_trilinear(uvec4 q, vec3 f) {
    vec2 a = unpackHalf2x16(q.x), b = unpackHalf2x16(q.y), c = unpackHalf2x16(q.z), d = unpackHalf2x16(q.w);
    float p0 = mix(mix(a.x, a.y, f.x), mix(b.x, b.y, f.x), f.y);
    float p1 = mix(mix(c.x, c.y, f.x), mix(d.x, d.y, f.x), f.y);
    return mix(p0, p1, f.z);
}

// The table from `base` at `x = sqrt(rho / reach)` (below 1), cos_phi and mu, with the critical
// cosine mu_c, in the channels of `mask` (bit c: channel c; 0 in the others); mu below mu_c
// reads the edge.
vec3 beam_table_lookup(uint base, uint mask, float mu_c, float x, float cos_phi, float mu) {
    vec3 f;
    uint ix = bt_cell(x * float(BT_NX - 1u), BT_NX, f.x);
    uint iy = bt_cell((clamp(cos_phi, -1.0, 1.0) + 1.0) * 0.5 * float(BT_NY - 1u), BT_NY, f.y);
    uint iz = bt_cell(clamp((mu - mu_c) / (1.0 - mu_c), 0.0, 1.0) * float(BT_NZ - 1u), BT_NZ, f.z);
    uint cell = base + (iz * (BT_NY - 1u) + iy) * (BT_NX - 1u) + ix;
    vec3 v = vec3(0.0);
    for (uint c = 0u; c < 3u; ++c) {
        if ((mask & (1u << c)) != 0u) v[c] = bt_trilinear(beam_tables[cell + c * BT_CELLS], f);
    }
    return v;
}

#endif

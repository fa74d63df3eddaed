// The between-points single-scattering kernel as a table: the f32 twin of
// BeamTable::lookup (src/optics/beam_table.rs, whose module doc says what is tabulated and why).
// Values at grid nodes over x = sqrt(rho / reach), cos phi in [-1, 1] and mu in [mu_c, 1],
// stored [(iz * NY + iy) * NX + ix] from an object's base in `beam_tables`, one vec4 per node
// with the object's channels (their reach is the same distance: render::beam_gather), read
// trilinearly. Include after declaring the vec4 array `beam_tables`.
#ifndef BEAM_TABLE_GLSL
#define BEAM_TABLE_GLSL

const uint BT_NX = 48u;
const uint BT_NY = 13u;
const uint BT_NZ = 9u;

// A grid coordinate's cell and fraction, the last cell taking the upper edge.
uint bt_cell(float x, uint n, out float f) {
    uint i = min(uint(max(floor(x), 0.0)), n - 2u);
    f = x - float(i);
    return i;
}

vec3 bt_at(uint base, uint ix, uint iy, uint iz) {
    return beam_tables[base + (iz * BT_NY + iy) * BT_NX + ix].rgb;
}

// The table from `base` at `x = sqrt(rho / reach)` (below 1), cos_phi and mu, with the critical
// cosine mu_c; mu below mu_c reads the edge.
vec3 beam_table_lookup(uint base, float mu_c, float x, float cos_phi, float mu) {
    float fx, fy, fz;
    uint ix = bt_cell(x * float(BT_NX - 1u), BT_NX, fx);
    uint iy = bt_cell((clamp(cos_phi, -1.0, 1.0) + 1.0) * 0.5 * float(BT_NY - 1u), BT_NY, fy);
    uint iz = bt_cell(clamp((mu - mu_c) / (1.0 - mu_c), 0.0, 1.0) * float(BT_NZ - 1u), BT_NZ, fz);
    vec3 p0 = mix(mix(bt_at(base, ix, iy, iz), bt_at(base, ix + 1u, iy, iz), fx),
                   mix(bt_at(base, ix, iy + 1u, iz), bt_at(base, ix + 1u, iy + 1u, iz), fx), fy);
    vec3 p1 = mix(mix(bt_at(base, ix, iy, iz + 1u), bt_at(base, ix + 1u, iy, iz + 1u), fx),
                   mix(bt_at(base, ix, iy + 1u, iz + 1u), bt_at(base, ix + 1u, iy + 1u, iz + 1u), fx), fy);
    return mix(p0, p1, fz);
}

// The table at normal incidence (mu = 1, where phi does not matter): its last row, read
// linearly in x as the trilinear lookup reads it there.
vec3 beam_table_normal(uint base, float x) {
    float fx;
    uint ix = bt_cell(x * float(BT_NX - 1u), BT_NX, fx);
    return mix(bt_at(base, ix, BT_NY - 1u, BT_NZ - 1u), bt_at(base, ix + 1u, BT_NY - 1u, BT_NZ - 1u), fx);
}

#endif

// The dipole sum at one receiver, shared by the vertex gather (gather.comp) and the pixel
// gather (gather_pixel.comp): the far kernel summed with Kahan compensation plus the near
// exitance blended over neighbouring samples (src/optics/kernel.rs, far_kernel's doc):
//     M(x) = sum_i E_i far_kernel(r_i, A_i) + sum_i phi_i E_i E_near,i / sum_i phi_i
// Include after dipole.glsl and scene.glsl.
#ifndef GATHER_GLSL
#define GATHER_GLSL

struct GatherSum {
    vec3 far;
    vec3 compensation;
    vec3 near_sum;
    float weight_sum;
    float nearest_r;
    vec3 nearest_near;
};

GatherSum gather_begin() {
    return GatherSum(vec3(0.0), vec3(0.0), vec3(0.0), 0.0, 3.4e38, vec3(0.0));
}

DipoleChannel[3] gather_channels(ObjectRecord o) {
    return o.dipole;
}

// Add one sample (position and area, transmitted irradiance E, near energy per channel).
void gather_add(inout GatherSum g, DipoleChannel ch[3], vec3 x, vec4 position_area, vec3 e, vec3 near_energy) {
    float r = distance(x, position_area.xyz);
    vec3 term;
    for (int c = 0; c < 3; ++c) {
        term[c] = e[c] * dipole_far_kernel(ch[c], r, position_area.w);
    }
    // Kahan summation; `precise` keeps the compiler from reassociating it away.
    precise vec3 y = term - g.compensation;
    precise vec3 t = g.far + y;
    precise vec3 c = (t - g.far) - y;
    g.compensation = c;
    g.far = t;
    vec3 near_exitance = e * near_energy;
    float w = dipole_near_blend_weight(r, position_area.w);
    g.near_sum += w * near_exitance;
    g.weight_sum += w;
    if (r < g.nearest_r) {
        g.nearest_r = r;
        g.nearest_near = near_exitance;
    }
}

// The radiant exitance; never negative.
vec3 gather_end(GatherSum g) {
    vec3 near = g.weight_sum > 0.0 ? g.near_sum / g.weight_sum : g.nearest_near;
    return max(g.far + near, vec3(0.0));
}

#endif

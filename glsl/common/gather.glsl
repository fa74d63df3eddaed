// The dipole sum at one receiver, shared by the vertex gather (gather.comp) and the pixel
// gather (gather_pixel.comp): the far kernel summed with Kahan compensation plus the near
// exitance blended over neighbouring samples (src/optics/kernel.rs, far_kernel's doc):
//     M(x) = sum_i E_i far_kernel(r_i, A_i) + sum_i phi_i E_i E_near,i / sum_i phi_i
// with a blend radius per channel (kernel::near_blend_radii, ObjectRecord::near_blend).
// Include after dipole.glsl and scene.glsl.
#ifndef GATHER_GLSL
#define GATHER_GLSL

// mesh::NO_BOUNDARY: the distance stored where no open boundary is near (f32::MAX).
const float GATHER_NO_BOUNDARY = 3.40282347e38;

struct GatherSum {
    vec3 far;            // Kahan-compensated far sum of the flushed terms
    vec3 compensation;
    vec3 partial;        // plain f32 sum of the terms since the last gather_flush
    vec3 near_sum;       // per channel, each with its own blend radius
    vec3 weight_sum;
    vec3 area_sum;       // sum of w A over the blend: its mean area sets b for the edge factor
    float nearest_r_sq;
    vec3 nearest_near;
};

GatherSum gather_begin() {
    return GatherSum(vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), 3.4e38, vec3(0.0));
}

DipoleChannel[3] gather_channels(ObjectRecord o) {
    return o.dipole;
}

// Add one sample (position and area, transmitted irradiance E, near energy per channel);
// `blend_inv_k_sq` is ObjectRecord::near_blend.rgb, 1 / k^2 per channel. The kernel's b^2 and
// the blend radii^2 are multiples of the area, so no square root is taken here beyond the
// poles' own; distances stay squared, and one division serves the three radii.
void gather_add(inout GatherSum g, DipoleChannel ch[3], vec3 blend_inv_k_sq, vec3 x, vec4 position_area, vec3 e, vec3 near_energy) {
    vec3 d = x - position_area.xyz;
    float r_sq = dot(d, d);
    float area = position_area.w;
    float beta = DIPOLE_B_PER_SQRT_AREA * DIPOLE_B_PER_SQRT_AREA * area;
    vec3 term;
    for (int c = 0; c < 3; ++c) {
        term[c] = e[c] * area * dipole_r_d_far_sq(ch[c], r_sq, beta);
    }
    g.partial += area > 0.0 ? term : vec3(0.0);
    // Shepard weights (1 - r^2/R^2)^3 inside R = k sqrt(area), per channel (dipole_near_blend_weight).
    vec3 t = vec3(1.0) - (r_sq / area) * blend_inv_k_sq;
    // A select, not max(): at zero area and distance the quotient is NaN.
    t = mix(vec3(0.0), t, greaterThan(t, vec3(0.0)));
    vec3 w = t * t * t;
    vec3 near_exitance = e * near_energy;
    g.near_sum += w * near_exitance;
    g.weight_sum += w;
    g.area_sum += w * area;
#ifdef GATHER_TRACK_NEAREST
    // Gathers without the sample hierarchy track the nearest sample for the fallback where no
    // Shepard weight reaches; the others find it afterwards by walking the hierarchy, which
    // costs nothing per pair (glsl/common/tree.glsl).
    if (r_sq < g.nearest_r_sq) {
        g.nearest_r_sq = r_sq;
        g.nearest_near = near_exitance;
    }
#endif
}

// Move the partial sum into the compensated one (Kahan): callers flush every 64 terms or so, so
// the plain sums stay short and the f32 total stays within 1e-3 of the f64 reference at any
// sample count while paying for compensation once per tile rather than per pair. `precise`
// keeps the compiler from reassociating it away.
void gather_flush(inout GatherSum g) {
    precise vec3 y = g.partial - g.compensation;
    precise vec3 t = g.far + y;
    precise vec3 c = (t - g.far) - y;
    g.compensation = c;
    g.far = t;
    g.partial = vec3(0.0);
}

// Per channel, the share of the blended near exitance a receiver keeps beside open boundaries
// `boundary` away (the two nearest directions, mesh::Mesh::boundary_distances; NO_BOUNDARY far
// from any), for samples of mean area `area` per channel (optics::kernel::near_kept_at_edge,
// once per side; reference::near_kept is the twin).
vec3 gather_near_kept(DipoleChannel ch[3], vec3 area, vec2 boundary) {
    vec3 b = DIPOLE_B_PER_SQRT_AREA * sqrt(area);
    vec3 kept;
    for (int c = 0; c < 3; ++c) {
        kept[c] = dipole_near_kept_at_edge(ch[c], b[c], boundary.x) * dipole_near_kept_at_edge(ch[c], b[c], boundary.y);
    }
    return kept;
}

// The radiant exitance; never negative. `boundary` as gather_near_kept takes it: the near
// field's energy past an open boundary leaves the surface (the nearest-sample fallback, where no
// blend weight reaches, keeps all).
vec3 gather_end(GatherSum g, DipoleChannel ch[3], vec2 boundary) {
    gather_flush(g);
    // Per channel: the blend where a weight reached, else the nearest sample's (whose area sum
    // is 0 too, so its edge factor is 1 and unused).
    bvec3 blended = greaterThan(g.weight_sum, vec3(0.0));
    vec3 weight = mix(vec3(1.0), g.weight_sum, blended);
    vec3 kept = gather_near_kept(ch, g.area_sum / weight, boundary);
    return max(g.far + mix(g.nearest_near, g.near_sum / weight * kept, blended), vec3(0.0));
}

#endif

// Forward shading, fragment stage: linear HDR radiance.
// Translucent: the BSSRDF's outgoing lobe turns exitance into radiance,
//     L_o = M F_t(cos theta_o, eta) / (pi T(eta))         (seed Eq. 9 normalized, Dipole::s_d),
// plus a dielectric GGX specular lobe per light. Opaque: Lambert plus GGX. Key lights are
// evaluated per pixel, shadowed with their shadow maps (4-tap PCF, or one tap where the planner
// finds a texel small on screen: render::plan::SHADOW_ONE_TAP_PIXELS); the environment's directions
// reach diffuse surfaces through the per-vertex irradiance cached by vertex_light.comp (and
// translucent ones through the splat and gather), and add no specular lobe.
// Bindings: 0 = lights (Light[]), 1 = shadow maps; the object's material comes in the push block.
// Compiled twice: shade.frag (vertex gather: exitance arrives interpolated from the vertices)
// and shade_pixel.frag (PIXEL_GATHER: a second attachment receives each pixel's world position
// and translucent object, and the HDR alpha the factor F_t / (pi T) that gather_pixel.comp
// multiplies the pixel's gathered exitance by).
#ifndef SHADE_GLSL
#define SHADE_GLSL
#include "dipole.glsl"
#include "lights.glsl"
#include "scene.glsl"

// SHADE_COMPUTE (the benchmark's shading over a G-buffer, glsl/bench/shade_compute.comp) takes
// shade_radiance alone: it declares its own inputs and the three constants below.
#ifndef SHADE_COMPUTE
layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec3 v_exitance;
layout(location = 3) in vec3 v_environment;
layout(location = 0) out vec4 out_radiance;
#ifdef PIXEL_GATHER
layout(location = 1) out vec4 out_surface;  // xyz: world position; w: object index + 1, 0 if opaque
#endif

// Specialization constants: ShadePass makes a pipeline per translucent-or-opaque, per shadow
// filter and per kind of key lights, so none is a branch at run time (a CPU driver runs both
// sides of a branch it cannot prove uniform; the four-tap filter then cost its taps on every
// pixel).
layout(constant_id = 0) const bool SHADE_TRANSLUCENT = false;
layout(constant_id = 1) const int SHADE_SHADOW_RADIUS = 0;  // light_visibility's radius: 0 one tap, 1 four
// Every key light is directional: the point and spot lights' falloff, which would run (and read
// its light fields) for every pixel whatever the light, is left out.
layout(constant_id = 2) const bool SHADE_DIRECTIONAL_KEYS = false;
// The scene's key-light count, where it is small (ShadePass::new; 0: read counts.y): a loop of a
// constant count is unrolled, and each light's record is then read at a constant index, once for
// all the lanes, where a CPU driver loads a storage buffer at a varying index lane by lane.
layout(constant_id = 3) const uint SHADE_KEY_LIGHTS = 0u;
// A host's display output (`RendererOptions::output = Output::Display`): the tone map's curve
// at the scene's exposure applied here, so that a swapchain image (8-bit UNORM) can be the
// target itself; linear radiance otherwise.
layout(constant_id = 4) const bool SHADE_DISPLAY = false;
layout(constant_id = 5) const float SHADE_EXPOSURE = 1.0;
#endif
layout(std430, set = 0, binding = 0) readonly buffer Lights { Light lights[]; };
layout(set = 0, binding = 1) uniform sampler2DArrayShadow shadow_maps;
#include "shade_push.glsl"

// GGX / Trowbridge-Reitz microfacet specular (Walter et al. 2007) with the height-correlated
// Smith visibility term (Heitz 2014); returns f_s cos(theta_i) without the Fresnel factor.
float ggx_specular(vec3 n, vec3 wi, vec3 wo, float alpha) {
    vec3 h = normalize(wi + wo);
    float nh = max(dot(n, h), 0.0), ni = max(dot(n, wi), 0.0), no = max(dot(n, wo), 1e-4);
    float a2 = max(alpha * alpha, 1e-6);
    float d = nh * nh * (a2 - 1.0) + 1.0;
    float D = a2 / (DIPOLE_PI * d * d);
    float vi = no * sqrt(ni * ni * (1.0 - a2) + a2);
    float vo = ni * sqrt(no * no * (1.0 - a2) + a2);
    float V = 0.5 / max(vi + vo, 1e-7);
    return D * V * ni;
}

// Linear radiance towards the eye from the surface point `position` with interpolated normal
// `normal`, gathered exitance `exitance` and environment irradiance `environment` (the vertex
// stage's four interpolants); `exitance_to_radiance` receives F_t(cos theta_o) / (pi T).
vec3 shade_radiance(vec3 v_position, vec3 v_normal, vec3 v_exitance, vec3 v_environment, out float exitance_to_radiance) {
    vec3 n = normalize(v_normal);
    vec3 wo = normalize(push.eye_object.xyz - v_position);
    // Seen from behind (open meshes, the far side of a thin plane): shade the visible side.
    if (dot(n, wo) < 0.0) n = -n;
    float cos_o = max(dot(n, wo), 0.0);
    bool translucent = SHADE_TRANSLUCENT;
    float eta = translucent ? push.material.x : 1.5;
    float roughness = push.albedo_roughness.w;
    float alpha = max(roughness * roughness, 1e-3);
    vec3 radiance = vec3(0.0);
    exitance_to_radiance = !translucent ? 0.0
        : (shade_skips(SHADE_SKIP_FRESNEL) ? 1.0 : dipole_fresnel_transmittance(cos_o, eta)) * push.material.y;
    // Irradiance transmitted into a translucent surface here, for the channels the planner
    // computes locally: the environment's part arrives per vertex (vertex_light.comp weighs it
    // by F_t for translucent objects), the key lights' is added below.
    vec3 transmitted = translucent ? v_environment : vec3(0.0);
    if (!translucent) radiance += v_environment * (push.albedo_roughness.rgb / DIPOLE_PI);
    // The key lights come first in the buffer (scene::lights::prepare); counts.y of them.
    uint key_lights = SHADE_KEY_LIGHTS > 0u ? SHADE_KEY_LIGHTS : push.counts.y;
    for (uint l = 0u; l < key_lights; ++l) {
        vec3 wi, irradiance;
        if (SHADE_DIRECTIONAL_KEYS) {
            wi = lights[l].direction_cos.xyz;
            irradiance = lights[l].power_layer.rgb;
        } else {
            light_incidence(lights[l], v_position, wi, irradiance);
        }
        float cos_i = dot(n, wi);
        if (cos_i <= 0.0) continue;
        float v = shade_skips(SHADE_SKIP_SHADOW) ? 1.0 : light_visibility(lights[l], shadow_maps, v_position, n, SHADE_SHADOW_RADIUS);
        vec3 lit = irradiance * v;
        if (!shade_skips(SHADE_SKIP_SPECULAR)) {
            vec3 h = normalize(wi + wo);
            float fresnel = dipole_fresnel_reflectance(max(dot(wi, h), 0.0), eta);
            radiance += lit * (fresnel * ggx_specular(n, wi, wo, alpha));
        }
        if (!translucent) radiance += lit * (push.albedo_roughness.rgb / DIPOLE_PI * cos_i);
        else transmitted += lit * (cos_i * (shade_skips(SHADE_SKIP_FRESNEL) ? 1.0 : dipole_fresnel_transmittance(cos_i, eta)));
    }
    if (translucent) {
        // Gathered channels: the exitance interpolated from the vertices (zero under the pixel
        // gather, which adds its own afterwards). Local ones: M = R_d,total E_t, the dipole
        // integral when E_t is uniform over the profile's width (render::plan).
        vec3 gathered = gathered_channels(push.counts.z);
        // R_d,total is the record's albedo (ObjectRecord::new), not recomputed per pixel.
        radiance += mix(push.albedo_roughness.rgb * transmitted, v_exitance, gathered) * exitance_to_radiance;
    }
    return radiance;
}

#ifndef SHADE_COMPUTE
#include "tonemap.glsl"

// What the attachment takes: linear radiance, or with SHADE_DISPLAY display sRGB (non-finite
// radiance drawn black, as the tone map draws it).
vec4 shade_output(vec3 radiance) {
    if (!SHADE_DISPLAY) return vec4(radiance, 1.0);
    if (any(isnan(radiance)) || any(isinf(radiance))) radiance = vec3(0.0);
    return vec4(display_curve(radiance * SHADE_EXPOSURE), 1.0);
}

void main() {
    if (shade_skips(SHADE_SKIP_ALL)) {
        // The inputs the pipeline's shading reads, no more: an opaque surface's pipeline has no
        // use for the exitance, and an input read nowhere is not interpolated.
        out_radiance = shade_output((SHADE_TRANSLUCENT ? v_exitance : vec3(0.0)) + v_environment);
#ifdef PIXEL_GATHER
        out_surface = vec4(0.0);
#endif
        return;
    }
    float exitance_to_radiance;
    vec3 radiance = shade_radiance(v_position, v_normal, v_exitance, v_environment, exitance_to_radiance);
    // Nothing non-finite leaves this pass (the tone map counts any that would).
#ifdef PIXEL_GATHER
    out_radiance = vec4(radiance, exitance_to_radiance);
    out_surface = vec4(v_position, SHADE_TRANSLUCENT ? push.eye_object.w + 1.0 : 0.0);
#else
    out_radiance = shade_output(radiance);
#endif
}
#endif

#endif

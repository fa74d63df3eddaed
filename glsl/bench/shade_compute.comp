#version 450
// The shading pass's arithmetic (glsl/common/shade.glsl's shade_radiance, unchanged) run in a
// compute pass over a G-buffer (glsl/bench/raster_gbuffer.frag) instead of in the fragment
// stage: whether llvmpipe shades cheaper where every SIMD lane holds a covered pixel than in
// fragment blocks that small triangles leave part empty (issue 27's question). Every covered
// pixel is shaded as the translucent object with one-tap shadows and directional key lights,
// the built-in scene's bunny pipeline.
// Bindings: 0 = lights, 1 = shadow maps (as shade.glsl), 2 to 5 = the G-buffer, 6 = radiance out.
#define SHADE_COMPUTE
const bool SHADE_TRANSLUCENT = true;
const int SHADE_SHADOW_RADIUS = 0;
const bool SHADE_DIRECTIONAL_KEYS = true;
const uint SHADE_KEY_LIGHTS = 0u;
#include "shade.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 2) uniform sampler2D g_position;
layout(set = 0, binding = 3) uniform sampler2D g_normal;
layout(set = 0, binding = 4) uniform sampler2D g_exitance;
layout(set = 0, binding = 5) uniform sampler2D g_environment;
layout(set = 0, binding = 6, rgba32f) uniform writeonly image2D radiance_out;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance_out)))) return;
    vec4 position = texelFetch(g_position, p, 0);
    vec3 radiance = vec3(0.0);
    if (position.w != 0.0) {
        float exitance_to_radiance;
        radiance = shade_radiance(position.xyz, texelFetch(g_normal, p, 0).xyz, texelFetch(g_exitance, p, 0).xyz,
                                  texelFetch(g_environment, p, 0).xyz, exitance_to_radiance);
    }
    imageStore(radiance_out, p, vec4(radiance, 1.0));
}

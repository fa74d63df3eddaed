#version 450
// Tone map: linear HDR radiance -> display sRGB, 8 bits per channel packed in a uint.
// Exposure, then the display curve of tonemap.glsl (shared with the viewer's present pass).
// Non-finite input is mapped to black so a NaN can never reach an image (and is counted).
// Bindings: 0 = HDR image (combined sampler, nearest), 1 = packed RGBA8 output (storage),
// 2 = counters (storage): [0] = non-finite pixels seen. Push: TonemapPush.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D hdr;
layout(std430, set = 0, binding = 1) writeonly buffer Tonemapped { uint rgba8[]; };
layout(std430, set = 0, binding = 2) buffer Counters { uint non_finite; };
struct TonemapPush {
    uint width;
    uint height;
    float exposure;
};
layout(push_constant) uniform TonemapPushBlock { TonemapPush push; };

#include "tonemap.glsl"

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= push.width || p.y >= push.height) return;
    vec4 c = texelFetch(hdr, ivec2(p), 0);
    bool bad = any(isnan(c.rgb)) || any(isinf(c.rgb));
    if (bad) {
        atomicAdd(non_finite, 1u);
        c.rgb = vec3(0.0);
    }
    vec3 display = display_curve(c.rgb * push.exposure);
    rgba8[p.y * push.width + p.x] = packUnorm4x8(vec4(display, 1.0));
}

#version 450
// Tone map: linear HDR radiance -> display sRGB, 8 bits per channel packed in a uint.
// Exposure, then the ACES filmic curve fit of Narkowicz (2015), then the sRGB transfer function.
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

// The curve reaches 1 at x = 7.25 and clamps there; inputs are capped at 64 first so that its
// x^2 terms cannot overflow f32 (a radiance of 1e30 would give inf / inf = NaN, drawn black).
const float TONE_SATURATION = 64.0;

vec3 aces_narkowicz(vec3 x) {
    const float a = 2.51, b = 0.03, c = 2.43, d = 0.59, e = 0.14;
    return clamp((x * (a * x + b)) / (x * (c * x + d) + e), 0.0, 1.0);
}

vec3 srgb_encode(vec3 linear) {
    vec3 lo = linear * 12.92;
    vec3 hi = 1.055 * pow(linear, vec3(1.0 / 2.4)) - 0.055;
    return mix(hi, lo, lessThanEqual(linear, vec3(0.0031308)));
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= push.width || p.y >= push.height) return;
    vec4 c = texelFetch(hdr, ivec2(p), 0);
    bool bad = any(isnan(c.rgb)) || any(isinf(c.rgb));
    if (bad) {
        atomicAdd(non_finite, 1u);
        c.rgb = vec3(0.0);
    }
    vec3 display = srgb_encode(aces_narkowicz(min(max(c.rgb, vec3(0.0)) * push.exposure, vec3(TONE_SATURATION))));
    rgba8[p.y * push.width + p.x] = packUnorm4x8(vec4(display, 1.0));
}

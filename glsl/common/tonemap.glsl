// The display curve: exposure-scaled linear radiance -> display sRGB in [0, 1]. The ACES filmic
// curve fit of Narkowicz (2015), then the sRGB transfer function. Shared by the tone-map pass
// (tonemap.comp, the renderer's own image) and the viewer's present pass, so that a window
// shows what `render` writes.

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

// Linear radiance, already scaled by the exposure, as display sRGB; negative input is black.
vec3 display_curve(vec3 scaled) {
    return srgb_encode(aces_narkowicz(min(max(scaled, vec3(0.0)), vec3(TONE_SATURATION))));
}

#version 450
// `translucent view`: the host's present pass. It reads the linear radiance translucent drew into
// the viewer's HDR image and writes display sRGB into the swapchain image (a UNORM format), with
// the tone-map pass's own curve, so the window shows what `translucent render` writes. While the
// user picks a light (Ctrl held), a ring marks where each light can be grabbed.
// Binding 0: the HDR image (combined sampler). Push: PresentPush. Non-finite pixels are black.
layout(set = 0, binding = 0) uniform sampler2D hdr;
const uint MAX_MARKERS = 6;
struct PresentPush {
    float exposure;
    uint markers;          // rings to draw, at most MAX_MARKERS
    vec2 pad;
    vec4 marker[MAX_MARKERS];  // x, y in pixels, radius in pixels, 1 for the light being dragged
};
layout(push_constant) uniform PresentPushBlock { PresentPush push; };
layout(location = 0) out vec4 color;

#include "tonemap.glsl"

void main() {
    vec3 c = texelFetch(hdr, ivec2(gl_FragCoord.xy), 0).rgb;
    if (any(isnan(c)) || any(isinf(c))) c = vec3(0.0);
    vec3 display = display_curve(c * push.exposure);
    for (uint i = 0; i < min(push.markers, MAX_MARKERS); i++) {
        vec4 m = push.marker[i];
        float d = abs(distance(gl_FragCoord.xy, m.xy) - m.z);
        if (d < 1.5) display = m.w > 0.5 ? vec3(1.0, 0.8, 0.1) : vec3(0.2, 0.8, 1.0);
    }
    color = vec4(display, 1.0);
}

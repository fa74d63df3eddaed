#version 450
// `translucent view`: the host's present pass. It reads the linear radiance translucent drew into
// the viewer's HDR image and writes display sRGB into the swapchain image (a UNORM format), with
// the tone-map pass's own curve, so the window shows what `translucent render` writes.
// Binding 0: the HDR image (combined sampler). Push: exposure. Non-finite pixels are black.
layout(set = 0, binding = 0) uniform sampler2D hdr;
layout(push_constant) uniform PresentPush { float exposure; } push;
layout(location = 0) out vec4 color;

#include "tonemap.glsl"

void main() {
    vec3 c = texelFetch(hdr, ivec2(gl_FragCoord.xy), 0).rgb;
    if (any(isnan(c)) || any(isinf(c))) c = vec3(0.0);
    color = vec4(display_curve(c * push.exposure), 1.0);
}

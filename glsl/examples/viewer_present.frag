#version 450
// `translucent view`: rings over the swapchain image where the lights can be grabbed, drawn
// while the user picks one (Ctrl held). translucent has already drawn the image in display
// values (`Output::Display`); every pixel off a ring is left as it is (discarded).
// Push: PresentPush.
const uint MAX_MARKERS = 6;
struct PresentPush {
    uint markers;          // rings to draw, at most MAX_MARKERS
    uint pad0;
    vec2 pad;
    vec4 marker[MAX_MARKERS];  // x, y in pixels, radius in pixels, 1 for the light being dragged
};
layout(push_constant) uniform PresentPushBlock { PresentPush push; };
layout(location = 0) out vec4 color;

void main() {
    for (uint i = 0; i < min(push.markers, MAX_MARKERS); i++) {
        vec4 m = push.marker[i];
        if (abs(distance(gl_FragCoord.xy, m.xy) - m.z) < 1.5) {
            color = m.w > 0.5 ? vec4(1.0, 0.8, 0.1, 1.0) : vec4(0.2, 0.8, 1.0, 1.0);
            return;
        }
    }
    discard;
}

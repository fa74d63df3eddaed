#version 450
// The benchmark's tone-map yardstick (benches/render/roofline.rs): the tone map's reads and
// writes (the HDR image texel by texel into packed RGBA8) with a clamp for a curve.
// Bindings: 0 = HDR image (combined sampler), 1 = packed RGBA8 output. Push: the image size.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D hdr;
layout(std430, set = 0, binding = 1) writeonly buffer Tonemapped { uint rgba8[]; };
layout(push_constant) uniform MinimalPushBlock { uvec2 size; } push;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= push.size.x || p.y >= push.size.y) return;
    rgba8[p.y * push.size.x + p.x] = packUnorm4x8(clamp(texelFetch(hdr, ivec2(p), 0), 0.0, 1.0));
}

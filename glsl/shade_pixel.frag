#version 450
// Forward shading, fragment stage, for the pixel gather: also writes each pixel's surface for
// gather_pixel.comp. The body is glsl/common/shade.glsl.
#define PIXEL_GATHER
#include "shade.glsl"

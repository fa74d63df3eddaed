#version 450
// Forward shading, fragment stage, for the vertex gather. The body is glsl/common/shade.glsl,
// shared with shade_pixel.frag.
#include "shade.glsl"

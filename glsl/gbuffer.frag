#version 460
// G-buffer: the interpolated world normal as its octahedral code (`gbuffer_code` in common.glsl, 4
// bytes a pixel; the clear value's 0 off the object). The passes take ω_o from the pixel's camera
// ray (`shaded` in pass.glsl), so no position is stored: on llvmpipe writing one is a second set of
// stores at every covered pixel, a sizeable part of the rasterising.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
layout(location = 0) in vec3 in_normal;
layout(location = 0) out uint out_code;

void main() {
    out_code = gbuffer_code(in_normal);
}

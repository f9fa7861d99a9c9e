#version 460
// Paper §4 diffuse pass: ρ_d/π · E(n), E from the 9 SH coefficients of the environment's
// irradiance (Ramamoorthi & Hanrahan 2001; the coefficients arrive multiplied by Â_l). Over the
// list of shaded pixels (compact.comp), like the lobe passes: cheaper on llvmpipe than the
// image-wide dispatch with early returns, where a vector of pixels off the mesh still runs the
// pass masked; the same pixels, the same image.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#define PIXELS_BINDING 4
#include "pass.glsl"
#include "diffuse.glsl"
// Over the list of shaded pixels (compact.comp).
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, r32ui) readonly uniform uimage2D gnrm;  // gbuffer_code
layout(set = 0, binding = 1, rgba32f) uniform image2D accum;
layout(std430, set = 0, binding = 2) readonly buffer Sh { vec4 c[9]; } sh;
// params.x = 1: the key estimator's lights, added as distant sources (`GpuKeyLights::cones`).
layout(std430, set = 0, binding = 3) readonly buffer Lights { uvec4 count; vec4 v[]; } lights;

void main() {
    DiffuseLight d;
    READ_DIFFUSE_LIGHT(d, sh, lights, pc.params.x != 0u);
    ivec2 p;
    if (!listed_pixel(p)) return;
    vec3 nrm = normalize(gbuffer_texel(imageLoad(gnrm, p).x).xyz);
    vec4 acc = imageLoad(accum, p);
    acc.rgb += pc.fparams.rgb / PI * diffuse_irradiance(d, nrm);
    imageStore(accum, p, acc);
}

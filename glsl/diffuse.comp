#version 460
// Paper §4 diffuse pass: ρ_d/π · E(n), E from the 9 SH coefficients of the environment's
// irradiance (Ramamoorthi & Hanrahan 2001; the coefficients arrive multiplied by Â_l). Over the
// list of shaded pixels (compact.comp), like the lobe passes: session 21, at 512² on the bench's
// material 4.2 → 3.0 ms (`key`), 3.1 → 2.2 (`fis`) against the image-wide dispatch with early
// returns, alternating binaries; the same pixels, the same image.
#extension GL_GOOGLE_include_directive : require
#define PIXELS_BINDING 4
#include "pass.glsl"
// Over the list of shaded pixels (compact.comp).
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, rgba32f) readonly uniform image2D gnrm;
layout(set = 0, binding = 1, rgba32f) uniform image2D accum;
layout(std430, set = 0, binding = 2) readonly buffer Sh { vec4 c[9]; } sh;
// params.x = 1: the key estimator's lights, added as distant sources (`GpuKeyLights::cones`).
layout(std430, set = 0, binding = 3) readonly buffer Lights { uvec4 count; vec4 v[]; } lights;

vec3 irradiance(vec3 c[9], vec3 n) {
    float x = n.x, y = n.y, z = n.z;
    return c[0] * 0.282095
        + c[1] * (0.488603 * y) + c[2] * (0.488603 * z) + c[3] * (0.488603 * x)
        + c[4] * (1.092548 * x * y) + c[5] * (1.092548 * y * z)
        + c[6] * (0.315392 * (3.0 * z * z - 1.0)) + c[7] * (1.092548 * x * z)
        + c[8] * (0.546274 * (x * x - y * y));
}

void main() {
    // The coefficients are read before any branch: llvmpipe broadcasts a uniform storage-buffer read
    // only where no lane is masked off (issue 10's profile: 27 → 4.4 ms at 512²).
    vec3 c[9];
    for (int k = 0; k < 9; k++) c[k] = sh.c[k].rgb;
    uint n = pc.params.x != 0u ? min(lights.count.x, 4u) : 0u;
    vec4 dir[4], power[4];
    for (uint k = 0u; k < 4u; k++) {
        uint j = min(k, max(n, 1u) - 1u);
        dir[k] = pc.params.x != 0u ? lights.v[2u * j] : vec4(0.0);
        // Zero past the lights: the sum below runs over all four (a loop of constant count, unrolled;
        // a `for (k < n)` loop costs a body more on llvmpipe, see pass.glsl).
        power[k] = pc.params.x != 0u && k < n ? lights.v[2u * j + 1u] : vec4(0.0);
    }
    ivec2 p;
    if (!listed_pixel(p)) return;
    vec3 nrm = normalize(imageLoad(gnrm, p).xyz);
    vec4 acc = imageLoad(accum, p);
    vec3 e = irradiance(c, nrm);
    for (uint k = 0u; k < 4u; k++) e += power[k].rgb * max(dot(nrm, dir[k].xyz), 0.0);
    acc.rgb += pc.fparams.rgb / PI * e;
    imageStore(accum, p, acc);
}

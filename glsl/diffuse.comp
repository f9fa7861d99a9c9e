#version 460
// Paper §4 diffuse pass: ρ_d/π · E(n), E from the 9 SH coefficients of the environment's
// irradiance (Ramamoorthi & Hanrahan 2001; the coefficients arrive multiplied by Â_l).
#extension GL_GOOGLE_include_directive : require
#include "pass.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) readonly uniform image2D gpos;
layout(set = 0, binding = 1, rgba32f) readonly uniform image2D gnrm;
layout(set = 0, binding = 2, rgba32f) uniform image2D accum;
layout(std430, set = 0, binding = 3) readonly buffer Sh { vec4 c[9]; } sh;

vec3 irradiance(vec3 n) {
    float x = n.x, y = n.y, z = n.z;
    return sh.c[0].rgb * 0.282095
        + sh.c[1].rgb * (0.488603 * y) + sh.c[2].rgb * (0.488603 * z) + sh.c[3].rgb * (0.488603 * x)
        + sh.c[4].rgb * (1.092548 * x * y) + sh.c[5].rgb * (1.092548 * y * z)
        + sh.c[6].rgb * (0.315392 * (3.0 * z * z - 1.0)) + sh.c[7].rgb * (1.092548 * x * z)
        + sh.c[8].rgb * (0.546274 * (x * x - y * y));
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!inside(p)) return;
    vec4 P = imageLoad(gpos, p);
    if (P.w < 0.5) return;
    vec3 n = normalize(imageLoad(gnrm, p).xyz);
    if (dot(n, pc.eye.xyz - P.xyz) <= 0.0) return;
    vec4 acc = imageLoad(accum, p);
    acc.rgb += pc.fparams.rgb / PI * irradiance(n);
    imageStore(accum, p, acc);
}

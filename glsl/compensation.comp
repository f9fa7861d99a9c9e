#version 460
// The energy compensation of the reciprocal lobes (docs/model.md, Energy preservation; docs/renderer.md,
// Energy compensation) over the list of shaded pixels, after the lobe passes: lobe k adds
// ρ_k (1 − Ê_k(ω_o)) c_k I_k, with I_k = ∫ (1 − Ê_k(ω_i)) L(ω_i) cos⁺θ_i dω_i, which does not depend on
// ω_o. The kernel K_k = (1 − Ê_k) cos⁺θ of the local frame arrives projected on the SH bands l ≤ 2 as a
// quadratic form a + b·ω + ωᵀCω (C traceless; `compensation::kernel`, with the integral's constants
// 4π, 4π/3 and 8π/15 and C's off-diagonal doubled folded in), the environment as its SH9 irradiance
// (diffuse.glsl), which is turned into radiance and rotated into the pixel's frame once. Then
// I_k = a α + b·β + Σ C_ij Γ_ij: exact for the map's bands l ≤ 2. With the `key` estimator's lights
// (params.x = 1) the coefficients are the residual map's and each light adds
// power (1 − Ê_k(d)) max(d_z, 0), as in the diffuse term.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#define PIXELS_BINDING 7
#include "pass.glsl"
#include "diffuse.glsl"
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, r32ui) readonly uniform uimage2D gnrm;  // gbuffer_code
layout(set = 0, binding = 1, rgba32f) uniform image2D accum;
layout(std430, set = 0, binding = 2) readonly buffer Sh { vec4 c[9]; } sh;
layout(std430, set = 0, binding = 3) readonly buffer Lights { uvec4 count; vec4 v[]; } lights;
#define MATERIAL_BINDING 4
#define TABLES_BINDING 5
#include "material.glsl"
// Per lobe three vec4: (a, b), (C_xx, C_yy, C_zz, C_xy), (C_xz, C_yz, 0, 0).
layout(std430, set = 0, binding = 6) readonly buffer Kernels { vec4 v[]; } kernels;

void main() {
    DiffuseLight d;
    READ_DIFFUSE_LIGHT(d, sh, lights, pc.params.x != 0u);
    ivec2 p;
    if (!listed_pixel(p)) return;
    Frame f;
    vec3 wo;
    if (!shaded(p, gbuffer_texel(imageLoad(gnrm, p).x), f, wo)) return;
    // Radiance L = α + β·ω + ωᵀΓω from the irradiance coefficients (divided by Â_l = π, 2π/3, π/4),
    // in world axes, then β and Γ in the pixel's frame (e_0 = t, e_1 = b, e_2 = n).
    vec3 alpha = d.c[0] * (0.282095 / PI);
    vec3 bw[3] = vec3[3](d.c[3], d.c[1], d.c[2]);
    const float B = 0.488603 * 1.5 / PI, G = 0.546274 * 4.0 / PI, Z = 0.315392 * 4.0 / PI;
    vec3 gw[3][3];
    gw[0][0] = G * d.c[8] - Z * d.c[6];
    gw[1][1] = -G * d.c[8] - Z * d.c[6];
    gw[2][2] = 2.0 * Z * d.c[6];
    gw[0][1] = G * d.c[4]; gw[1][0] = gw[0][1];
    gw[1][2] = G * d.c[5]; gw[2][1] = gw[1][2];
    gw[0][2] = G * d.c[7]; gw[2][0] = gw[0][2];
    mat3 e = transpose(mat3(f.t, f.b, f.n));  // rows t, b, n
    vec3 beta[3], gamma[3][3];
    [[unroll]] for (int i = 0; i < 3; i++) {
        beta[i] = B * (e[0][i] * bw[0] + e[1][i] * bw[1] + e[2][i] * bw[2]);
    }
    [[unroll]] for (int i = 0; i < 3; i++) {
        [[unroll]] for (int j = i; j < 3; j++) {
            vec3 s = vec3(0.0);
            [[unroll]] for (int a = 0; a < 3; a++) {
                [[unroll]] for (int b = 0; b < 3; b++) s += (e[a][i] * e[b][j]) * gw[a][b];
            }
            gamma[i][j] = s;
        }
    }
    vec3 dl[4];
    [[unroll]] for (int k = 0; k < 4; k++) dl[k] = to_local(f, d.dir[k].xyz);
    vec3 sum = vec3(0.0);
    uint count = brdf_lobe_count(), k = 0u;
    if (count > 0u) do {
        float uo = 1.0 - brdf_table_albedo(k, wo);
        vec4 k0 = kernels.v[3u * k], k1 = kernels.v[3u * k + 1u], k2 = kernels.v[3u * k + 2u];
        vec3 irr = k0.x * alpha + k0.y * beta[0] + k0.z * beta[1] + k0.w * beta[2]
                 + k1.x * gamma[0][0] + k1.y * gamma[1][1] + k1.z * gamma[2][2] + k1.w * gamma[0][1]
                 + k2.x * gamma[0][2] + k2.y * gamma[1][2];
        // The slots past the lights' count have no power (the same for every pixel, so the test
        // skips their lookups everywhere).
        [[unroll]] for (int j = 0; j < 4; j++) {
            if (d.power[j].r + d.power[j].g + d.power[j].b > 0.0 && dl[j].z > 0.0)
                irr += d.power[j].rgb * ((1.0 - brdf_table_albedo(k, dl[j])) * dl[j].z);
        }
        sum += brdf_lobe(k).albedo.rgb * ((uo * brdf_table_float(8u * k + 5u)) * max(irr, vec3(0.0)));
    } while (++k < count);
    vec4 acc = imageLoad(accum, p);
    acc.rgb += sum;
    imageStore(accum, p, acc);
}

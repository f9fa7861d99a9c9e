// The environment: lookups in the prefiltered equirect texture and importance sampling over
// |L| sin θ by CDF inversion (the tables of `src/scene/env.rs`: marginal over rows, conditional per
// row, and the per-texel pdf over (u, v)). The including shader declares, before including:
//   ENV_TEX (sampler2D), ENV_MARGINAL.v[H+1], ENV_CONDITIONAL.v[H*(W+1)], ENV_PDF.v[W*H],
//   and ENV_SIZE (uvec2: W, H).
#ifndef ENV_GLSL
#define ENV_GLSL
#include "common.glsl"

vec3 env_lookup(vec3 d, float lod) { return textureLod(ENV_TEX, equirect_uv(d), lod).rgb; }

// Largest index i in [first, first + count) with table[i] <= x (first when none). A do-while behind
// a check (pass.glsl's note on loops).
#define UPPER_SEARCH(TABLE, first, count, x, out_index) { \
    uint lo = 0u, hi = (count); \
    if (hi - lo > 1u) do { \
        uint mid = (lo + hi) / 2u; if (TABLE[(first) + mid] <= (x)) lo = mid; else hi = mid; \
    } while (hi - lo > 1u); \
    out_index = lo; }

// Direction from (u1, u2) ∈ [0,1)², with its pdf over solid angle; false for an all-black map.
bool env_sample(float u1, float u2, out vec3 dir, out float pdf) {
    uint W = ENV_SIZE.x, H = ENV_SIZE.y;
    if (!(ENV_MARGINAL.v[H] > 0.0)) return false;
    uint j;
    UPPER_SEARCH(ENV_MARGINAL.v, 0u, H, u1, j);
    float c0 = ENV_MARGINAL.v[j], c1 = ENV_MARGINAL.v[j + 1u];
    float t = c1 > c0 ? clamp((u1 - c0) / (c1 - c0), 0.0, 1.0) : 0.5;
    uint row = j * (W + 1u);
    uint i;
    UPPER_SEARCH(ENV_CONDITIONAL.v, row, W, u2, i);
    float d0 = ENV_CONDITIONAL.v[row + i], d1 = ENV_CONDITIONAL.v[row + i + 1u];
    float s = d1 > d0 ? clamp((u2 - d0) / (d1 - d0), 0.0, 1.0) : 0.5;
    vec2 uv = vec2((float(i) + s) / float(W), (float(j) + t) / float(H));
    dir = equirect_dir(uv);
    float sin_t = sin(PI * uv.y);
    pdf = sin_t > 0.0 ? ENV_PDF.v[j * W + i] / (2.0 * PI * PI * sin_t) : 0.0;
    return pdf > 0.0;
}

float env_pdf(vec3 d) {
    uint W = ENV_SIZE.x, H = ENV_SIZE.y;
    vec2 uv = equirect_uv(d);
    uint i = min(uint(uv.x * float(W)), W - 1u), j = min(uint(uv.y * float(H)), H - 1u);
    float sin_t = sqrt(max(1.0 - d.y * d.y, 0.0));
    return sin_t > 0.0 ? ENV_PDF.v[j * W + i] / (2.0 * PI * PI * sin_t) : 0.0;
}

#endif

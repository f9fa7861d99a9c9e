#version 460
// The `mis` estimator: a full Monte Carlo estimate of the whole material (diffuse included) under
// the environment read at level 0. Per sample, one environment sample (CDF inversion over |L| sin θ)
// and one BRDF sample (the material's mixture), combined by the balance heuristic. A deterministic
// QMC sequence (Halton, bases 2, 3, 5, 7, 11 from index 1) is Cranley–Patterson rotated per pixel.
// Dispatched in chunks of samples; each chunk adds its share of the mean.
#extension GL_GOOGLE_include_directive : require
#define PIXELS_BINDING 8
#include "pass.glsl"
// Over the list of shaded pixels (compact.comp).
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, r32ui) readonly uniform uimage2D gnrm;  // gbuffer_code
layout(set = 0, binding = 1, rgba32f) uniform image2D accum;
layout(set = 0, binding = 2) uniform sampler2D env_tex;
#define MATERIAL_BINDING 3
#define MATERIAL_UNIFORM
#define TABLES_BINDING 9
#include "material.glsl"
layout(std430, set = 0, binding = 4) readonly buffer Qmc { vec4 v[]; } qmc; // 2 per sample
layout(std430, set = 0, binding = 5) readonly buffer Marginal { float v[]; } marginal;
layout(std430, set = 0, binding = 6) readonly buffer Conditional { float v[]; } conditional;
layout(std430, set = 0, binding = 7) readonly buffer EnvPdf { float v[]; } env_pdf_table;
#define ENV_TEX env_tex
#define ENV_MARGINAL marginal
#define ENV_CONDITIONAL conditional
#define ENV_PDF env_pdf_table
#define ENV_SIZE pc.size.zw
#include "env.glsl"

void main() {
    ivec2 p;
    if (!listed_pixel(p)) return;
    Frame f;
    vec3 wo;
    if (!shaded(p, gbuffer_texel(imageLoad(gnrm, p).x), f, wo)) return;
    uint pixel = uint(p.y) * pc.size.x + uint(p.x);
    vec4 rot0 = vec4(hash_unit(pixel * 5u), hash_unit(pixel * 5u + 1u), hash_unit(pixel * 5u + 2u), 0.0);
    vec2 rot1 = vec2(hash_unit(pixel * 5u + 3u), hash_unit(pixel * 5u + 4u));
    float w_diffuse;
    float total = mixture_total(wo, w_diffuse);
    vec3 sum = vec3(0.0);
    uint first = pc.params.z, count = pc.params.y;
    // A do-while: a dispatch has at least one sample (pass.glsl's note on loops).
    uint s = first;
    do {
        vec4 a = fract(qmc.v[2u * s] + rot0);
        vec2 e = fract(qmc.v[2u * s + 1u].xy + rot1);
        // Environment sample.
        vec3 dir;
        float pe;
        if (env_sample(e.x, e.y, dir, pe)) {
            vec3 wi = to_local(f, dir);
            if (wi.z > 0.0) {
                float pb = mixture_pdf(wo, wi, total, w_diffuse);
                vec3 c = material_eval(wi, wo) * textureLod(env_tex, equirect_uv(dir), 0.0).rgb * wi.z / (pe + pb);
                if (all(lessThan(abs(c), vec3(3e38)))) sum += c;
            }
        }
        // BRDF sample.
        vec3 wi;
        if (mixture_sample(wo, total, w_diffuse, a.x, 1.0 - a.y, a.z, wi)) {
            float pb = mixture_pdf(wo, wi, total, w_diffuse);
            vec3 d = to_world(f, wi);
            float pe2 = env_pdf(d);
            if (pb + pe2 > 0.0) {
                vec3 c = material_eval(wi, wo) * textureLod(env_tex, equirect_uv(d), 0.0).rgb * wi.z / (pe2 + pb);
                if (all(lessThan(abs(c), vec3(3e38)))) sum += c;
            }
        }
    } while (++s < first + count);
    vec4 acc = imageLoad(accum, p);
    acc.rgb += sum * pc.fparams.w;
    imageStore(accum, p, acc);
}

#version 460
// The `key` estimator's filter of its rough lobes (issue 10; `render/denoise.rs`): their lobe passes
// write into `rough` (rgb) with a sample set shifted per pixel, so each pixel's quadrature error is
// its own, and mark each pixel they shade with its normal (alpha: `normal_tag`; 0, as cleared, where
// they shade nothing). A lobe's outgoing radiance is smooth in the normal on the scale of its
// roughness α, and this filter averages over the pixels q near p with the weight
// exp(−(1 − n_p·n_q) / σ²), σ a fraction of the smallest α of those lobes: the noise of a few
// samples traded for a bias of second order in σ / α. A pixel whose neighbours face elsewhere (a
// silhouette, a crease) keeps its own value.
//
// Separable, as two passes of 2R + 1 taps over the shaded pixels (params.x 0: along x, `rough` →
// `mid`, cleared to unmarked before; 1: along y, `mid` → added into the accumulation image): one load a tap. The 49 taps
// of a (2R+1)² window, each a load of the G-buffer and of the value, cost more than a lobe pass on
// llvmpipe (image loads go lane by lane there).
#extension GL_GOOGLE_include_directive : require
#define PIXELS_BINDING 3
#include "pass.glsl"
#define R 3
// Over the list of shaded pixels (compact.comp).
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, rgba32f) readonly uniform image2D src;
layout(set = 0, binding = 1, rgba32f) uniform image2D mid;
layout(set = 0, binding = 2, rgba32f) uniform image2D accum;
// params.x: the direction (0: x, 1: y); fparams.x: 1 / σ².

// The normal of a tag (`normal_tag` in lobe.comp: 1 + the octahedral code of the normal, 11 bits a
// coordinate, an integer a float holds exactly).
vec3 tag_normal(float tag) {
    uint code = uint(tag - 1.0);
    vec2 e = vec2(float(code >> 11), float(code & 2047u)) * (2.0 / 2047.0) - 1.0;
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return normalize(n);
}

void main() {
    ivec2 p;
    if (!listed_pixel(p)) return;
    bool along_y = pc.params.x != 0u;
    // Marked: the lobe passes shade exactly the listed pixels.
    vec4 c = imageLoad(src, p);
    vec3 n = tag_normal(c.a);
    float k_p = pc.fparams.x;
    ivec2 step = along_y ? ivec2(0, 1) : ivec2(1, 0);
    ivec2 last = ivec2(pc.size.xy) - 1;
    // The centre with weight 1 (its own normal: exactly 1, not what rounding makes of the formula).
    vec3 sum = c.rgb;
    float wsum = 1.0;
    // A loop of constant count, unrolled.
    for (int k = -R; k <= R; k++) {
        if (k == 0) continue;
        vec4 t = imageLoad(src, clamp(p + k * step, ivec2(0), last));
        float w = t.a < 0.5 ? 0.0 : exp(-(1.0 - dot(n, tag_normal(t.a))) * k_p);
        sum += w * t.rgb;
        wsum += w;
    }
    vec3 v = sum / wsum;
    if (!along_y) {
        imageStore(mid, p, vec4(v, c.a));
    } else {
        vec4 acc = imageLoad(accum, p);
        acc.rgb += v;
        imageStore(accum, p, acc);
    }
}

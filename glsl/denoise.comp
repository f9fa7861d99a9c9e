#version 460
// The `key` estimator's filter of its rough lobes (`render/denoise.rs`): their lobe passes
// write into `rough` (rgb) with a sample set shifted per pixel, so each pixel's quadrature error is
// its own, and mark each pixel they shade with its normal (alpha: `normal_tag`; 0, as cleared, where
// they shade nothing). A lobe's outgoing radiance is smooth in the normal on the scale of its
// roughness α, and this filter averages over the pixels q near p with the weight
// exp(−(1 − n_p·n_q) / σ²), σ a fraction of the smallest α of those lobes: the noise of a few
// samples traded for a bias of second order in σ / α. A pixel whose neighbours face elsewhere (a
// silhouette, a crease) keeps its own value.
//
// Separable, as two passes of 2R + 1 taps (params.x 0: along x, `rough` → `mid`, every pixel
// written, unmarked ones as 0; 1: along y, `mid` → added into the accumulation image at the marked
// pixels). An invocation takes a run of STRIP pixels along the pass's direction: it reads the
// STRIP + 2R pixels under their windows once and decodes each normal once, where a pixel of its own
// would read and decode 2R + 1 (7 loads and 7 decodes a pixel a pass). The same sums, in the
// same order. Pixels off the image are read clamped to its edge. The 49 taps of a (2R+1)² window,
// each a load of the G-buffer and of the value, cost more than a lobe pass on llvmpipe (image loads
// go lane by lane there).
#extension GL_GOOGLE_include_directive : require
#include "pass.glsl"
#define R 3
#define STRIP 4
#define SPAN (STRIP + 2 * R)
// Over the image in runs of STRIP pixels (`denoise::groups`).
layout(local_size_x = 8, local_size_y = 8) in;
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
    bool along_y = pc.params.x != 0u;
    ivec2 step = along_y ? ivec2(0, 1) : ivec2(1, 0);
    ivec2 id = ivec2(gl_GlobalInvocationID.xy);
    // The run's first pixel.
    ivec2 first = along_y ? ivec2(id.x, STRIP * id.y) : ivec2(STRIP * id.x, id.y);
    if (!inside(first)) return;
    ivec2 last = ivec2(pc.size.xy) - 1;
    float k_p = pc.fparams.x;
    // The pixels under the run's windows: values, tags, and normals where marked. Constant indices
    // throughout (the loops unroll): the arrays stay in registers.
    vec4 c[SPAN];
    vec3 n[SPAN];
    for (int i = 0; i < SPAN; i++) {
        c[i] = imageLoad(src, clamp(first + (i - R) * step, ivec2(0), last));
        n[i] = c[i].a < 0.5 ? vec3(0.0) : tag_normal(c[i].a);
    }
    for (int j = 0; j < STRIP; j++) {
        ivec2 p = first + j * step;
        if (!inside(p)) continue;
        vec4 centre = c[j + R];
        vec3 v = vec3(0.0);
        if (centre.a >= 0.5) {
            // The centre with weight 1 (its own normal: exactly 1, not what rounding makes of the formula).
            vec3 sum = centre.rgb;
            float wsum = 1.0;
            for (int k = -R; k <= R; k++) {
                if (k == 0) continue;
                vec4 t = c[j + R + k];
                float w = t.a < 0.5 ? 0.0 : exp(-(1.0 - dot(n[j + R], n[j + R + k])) * k_p);
                sum += w * t.rgb;
                wsum += w;
            }
            v = sum / wsum;
        }
        if (!along_y) {
            imageStore(mid, p, vec4(v, centre.a));
        } else if (centre.a >= 0.5) {
            vec4 acc = imageLoad(accum, p);
            acc.rgb += v;
            imageStore(accum, p, acc);
        }
    }
}

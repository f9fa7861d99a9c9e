#version 460
// The sparse form of the `key` estimator's filter of its rough lobes (`render/denoise.rs`,
// `denoise::sparse`; the dense form and the weights: denoise.comp). Their lobe passes took one
// sample set per 2 × 2 block of pixels, at the block's first shaded pixel, and wrote its sum into
// `cells` (one texel a block, marked with that pixel's normal) and the lobe's light term into
// `cells_light`.
//
// Each shaded pixel p gets the normal-weighted mean of the blocks within R pixels of it along each
// axis (block c taken at pixel 2 c): along an even coordinate the blocks −1, 0, +1 of its own, along
// an odd one −1 … +2. (So an odd coordinate's window holds one of the 3 strata of the lobe passes'
// shifts twice, `lobe.comp` SPARSE; the outer two at half weight, which balances them, is no more
// accurate on the sweep's rough scenes: docs/renderer.md, Alternatives measured and rejected.) Its
// light term is interpolated bilinearly from the 2 × 2 nearest blocks (an even coordinate sits on
// its block, an odd one halfway to the next), normal-weighted too. An invocation takes one block's
// four pixels, whose windows together span its 4 × 4 neighbours, read once. The loops are unrolled
// and skip nothing (an unmarked block weighs 0): on llvmpipe the same loops with a `continue` cost
// more, since an `if` skips nothing there (docs/renderer.md, Alternatives measured and rejected).
// The pixel's own block is always marked (its list holds every block with a shaded pixel); where
// every weight underflows, the pixel takes that block's values.
//
// Dispatched over `compact.comp`'s list of blocks (those with a shaded pixel), not over the image:
// llvmpipe runs both sides of an `if` (pass.glsl), so a vector of blocks off the mesh would run the
// whole filter, masked (docs/renderer.md, Alternatives measured and rejected).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#define PIXELS_BINDING 4
#include "pass.glsl"
#include "diffuse.glsl"
// The window's radius in pixels (`denoise::RADIUS`): its blocks, 4 along an odd coordinate, are
// written out below.
#define R 3
#if R != 3
#error "the window's blocks below are those within 3 pixels"
#endif
// Over the list of blocks, each by its first shaded pixel (`compact.comp`).
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, rgba32f) readonly uniform image2D cells;
layout(set = 0, binding = 1, rgba32f) uniform image2D accum;
layout(set = 0, binding = 2, rgba32f) readonly uniform image2D cells_light;
// The G-buffer: each pixel's normal and whether it is shaded (`facing` in pass.glsl, as compact.comp
// listed it), read here instead of an image of every pixel's normal and mark written by
// compact.comp: one full-size image store less (on llvmpipe an image store goes lane by lane).
layout(set = 0, binding = 3, r32ui) readonly uniform uimage2D gnrm;  // gbuffer_code
// DIFFUSE: the frame's compact pass left the listed pixels at (0, 0, 0, 1) (`compact.comp` LATER),
// and each pixel takes the diffuse term here first, the same arithmetic (albedo fparams.rgb,
// params.x the key estimator's lights; stand-ins bound otherwise). Added before the filter's sums,
// to what the lobe passes added (a narrow lobe's light term at each pixel), as compact.comp's
// image started: x + d = d + x, so one such term gives the same image, bit for bit.
layout(constant_id = 0) const bool DIFFUSE = false;
layout(std430, set = 0, binding = 5) readonly buffer Sh { vec4 c[9]; } sh;
layout(std430, set = 0, binding = 6) readonly buffer Lights { uvec4 count; vec4 v[]; } lights;
DiffuseLight g_diffuse;
// fparams.w: log2(e) / σ².

// The normal of a tag (`normal_tag` in lobe.comp: 1 + the octahedral code of the normal, 11 bits a
// coordinate, an integer a float holds exactly); float arithmetic only.
vec3 tag_normal(float tag) {
    float code = tag - 1.0;
    float hi = floor(code * (1.0 / 2048.0));
    vec2 e = vec2(hi, code - 2048.0 * hi) * (2.0 / 2047.0) - 1.0;
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    vec2 folded = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    n.xy = n.z < 0.0 ? folded : n.xy;
    return n * inversesqrt(dot(n, n));
}

// Pixel p's normal, and whether it is shaded (listed by `compact.comp`).
bool pixel_normal(ivec2 p, out vec3 n) {
    ivec2 q = min(p, ivec2(pc.size.xy) - 1);
    return facing(q, gbuffer_texel(imageLoad(gnrm, q).x), n) && inside(p);
}

// Whether block i (0 … 3 for the blocks −1 … +2) is in the window along a coordinate of parity `odd`.
float along(int i, bool odd) {
    return odd || i < 3 ? 1.0 : 0.0;
}

// The bilinear weight of block i along a coordinate of parity `odd` (blocks 0 and +1 only).
float linear(int i, bool odd) {
    return odd ? (i == 1 || i == 2 ? 0.5 : 0.0) : (i == 1 ? 1.0 : 0.0);
}

// One block's part in a pixel's sums: its value t at normal weight w times the spatial weight
// `window` in `sum`, its light term L at w times the bilinear weight `lin` in `light`.
void add(vec3 t, vec3 L, float w, float window, float lin, inout vec4 sum, inout vec4 light) {
    sum += (w * window) * vec4(t, 1.0);
    light += (w * lin) * vec4(L, 1.0);
}

// Adds pixel p's means (sum.rgb / sum.a and light.rgb / light.a; its own block's values where every
// weight underflowed), after its diffuse term (DIFFUSE; n its normal).
void finish(ivec2 p, bool shaded, vec3 n, vec4 sum, vec4 light, vec3 own, vec3 own_light) {
    if (!shaded) return;
    vec4 acc = imageLoad(accum, p);
    if (DIFFUSE) acc.rgb += pc.fparams.rgb / PI * diffuse_irradiance(g_diffuse, n);
    acc.rgb += sum.a > 0.0 ? sum.rgb / sum.a : own;
    acc.rgb += light.a > 0.0 ? light.rgb / light.a : own_light;
    imageStore(accum, p, acc);
}

// The sums of a block's four pixels p … p + (1, 1) over their windows, added to the image.
void filter_block(ivec2 b, ivec2 p, ivec2 blocks, vec3 n0, vec3 n1, vec3 n2, vec3 n3, bool s0, bool s1, bool s2,
                  bool s3) {
    float k_p = pc.fparams.w;
    // Weighted sums (rgb) and weights (a) of the four pixels: pixel 1 is (1, 0) (an odd x), pixel 2
    // (0, 1), pixel 3 (1, 1).
    vec4 a0 = vec4(0.0), a1 = vec4(0.0), a2 = vec4(0.0), a3 = vec4(0.0);
    vec4 l0 = vec4(0.0), l1 = vec4(0.0), l2 = vec4(0.0), l3 = vec4(0.0);
    vec3 own = vec3(0.0), own_light = vec3(0.0);
    [[unroll]] for (int j = 0; j < 4; j++) {
        [[unroll]] for (int i = 0; i < 4; i++) {
            ivec2 q = b + ivec2(i - 1, j - 1);
            bool on = all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, blocks));
            ivec2 qc = clamp(q, ivec2(0), blocks - 1);
            vec4 t = imageLoad(cells, qc);
            bool near = i >= 1 && i <= 2 && j >= 1 && j <= 2;
            vec3 L = near ? imageLoad(cells_light, qc).rgb : vec3(0.0);
            if (i == 1 && j == 1) {
                own = t.rgb;
                own_light = L;
            }
            float mark = on && t.a > 0.5 ? 1.0 : 0.0;
            vec3 nq = tag_normal(max(t.a, 1.0));
            float w0 = mark * exp2((dot(n0, nq) - 1.0) * k_p), w1 = mark * exp2((dot(n1, nq) - 1.0) * k_p);
            float w2 = mark * exp2((dot(n2, nq) - 1.0) * k_p), w3 = mark * exp2((dot(n3, nq) - 1.0) * k_p);
            add(t.rgb, L, w0, along(i, false) * along(j, false), linear(i, false) * linear(j, false), a0, l0);
            add(t.rgb, L, w1, along(i, true) * along(j, false), linear(i, true) * linear(j, false), a1, l1);
            add(t.rgb, L, w2, along(i, false) * along(j, true), linear(i, false) * linear(j, true), a2, l2);
            add(t.rgb, L, w3, along(i, true) * along(j, true), linear(i, true) * linear(j, true), a3, l3);
        }
    }
    finish(p, s0, n0, a0, l0, own, own_light);
    finish(p + ivec2(1, 0), s1, n1, a1, l1, own, own_light);
    finish(p + ivec2(0, 1), s2, n2, a2, l2, own, own_light);
    finish(p + ivec2(1, 1), s3, n3, a3, l3, own, own_light);
}

void main() {
    // Before any branch (diffuse.glsl).
    if (DIFFUSE) READ_DIFFUSE_LIGHT(g_diffuse, sh, lights, pc.params.x != 0u);
    ivec2 first;
    if (!listed_pixel(first)) return;
    ivec2 b = first / 2;
    ivec2 blocks = ivec2((pc.size.xy + 1u) / 2u);
    ivec2 p = 2 * b;
    vec3 n0, n1, n2, n3;
    bool s0 = pixel_normal(p, n0), s1 = pixel_normal(p + ivec2(1, 0), n1);
    bool s2 = pixel_normal(p + ivec2(0, 1), n2), s3 = pixel_normal(p + ivec2(1, 1), n3);
    filter_block(b, p, blocks, n0, n1, n2, n3, s0, s1, s2, s3);
}

#version 460
// The mesh view's shaded pixels as a list: every pixel where the G-buffer holds the mesh and the
// surface faces the eye (`shaded` in pass.glsl, the test every mesh pass makes),
// appended in no particular order, and the dispatch that covers the list in groups of 64
// (`pixels.groups`, read by vkCmdDispatchIndirect). Built once per G-buffer.
//
// Why: on llvmpipe an early return only masks the lanes (pass.glsl's note on loops), so a vector of
// 8 pixels off the mesh still ran one round of every loop of those passes. Dispatched over the list,
// every vector but the last is 8 shaded pixels. Each pixel's value does not depend on its place in
// the list, so images are unchanged.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_EXT_control_flow_attributes : require
#include "pass.glsl"
#include "diffuse.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
// LATER: the frame's sparse filter (denoise_sparse.comp, which reads and writes every listed pixel
// anyway) adds the diffuse term, and the image was cleared to (0, 0, 0, 1) before this pass
// (`CompactPass::record`): nothing is stored here, and the background is left to the background
// pass over the blocks this one lists (binding 7). On llvmpipe an image store goes lane by lane,
// and a texture lookup runs for every lane whatever its mask, so the compact pass without its
// lookups and stores costs much less (docs/renderer.md, Alternatives measured and rejected). A
// constant, not a push constant: llvmpipe runs both sides of an `if`, so the code of both ways
// would run, masked, in every frame.
layout(constant_id = 0) const bool LATER = false;
// PIXELS: the list of pixels is written (the blocks' always). A frame whose passes all run over the
// blocks leaves it to the next frame that keeps the G-buffer and needs it (`compact::Start`): its
// appends are a cost on llvmpipe that nothing in such a frame would repay (docs/renderer.md,
// Alternatives measured and rejected).
layout(constant_id = 1) const bool PIXELS = true;
layout(set = 0, binding = 0, r32ui) readonly uniform uimage2D gnrm;  // gbuffer_code
// count, then groups (x, y, z) (the header written as (0, 0, 1, 1) before this pass), then x | y << 16.
layout(std430, set = 0, binding = 1) buffer Pixels { uint count; uint groups[3]; uint at[]; } pixels;
// The same for the 2 × 2 blocks of pixels with any pixel listed, each by its first listed pixel
// (in the order (0, 0), (1, 0), (0, 1), (1, 1)): the pixel whose samples a sparse filtered lobe
// pass takes for the block (`denoise::sparse`).
layout(std430, set = 0, binding = 2) buffer Blocks { uint count; uint groups[3]; uint at[]; } blocks;
// The frame's image, started here in a frame that rasterises (background.comp and diffuse.comp
// otherwise): the environment (level 0) behind the object with alpha 0, (0, 0, 0, 1) on it, plus the
// diffuse term at the listed pixels where params.y = 1 (albedo fparams.rgb, params.x the key
// estimator's lights, as diffuse.comp takes them); with LATER nothing (see above).
layout(set = 0, binding = 3, rgba32f) writeonly uniform image2D accum;
layout(set = 0, binding = 4) uniform sampler2D env_tex;
layout(std430, set = 0, binding = 5) readonly buffer Sh { vec4 c[9]; } sh;
layout(std430, set = 0, binding = 6) readonly buffer Lights { uvec4 count; vec4 v[]; } lights;
// LATER: the 2 × 2 blocks with a pixel inside the image and off the object, each by its top-left
// pixel, for the background pass over them (background.comp BLOCKS): on llvmpipe a texture lookup
// runs for every lane of a vector, so here it would run at every pixel of the image, three quarters
// of them on the object, at more cost than the background pass over the blocks (docs/renderer.md,
// Alternatives measured and rejected).
layout(std430, set = 0, binding = 7) buffer BackgroundBlocks { uint count; uint groups[3]; uint at[]; } background;

// Whether pixel p (inside the image or not) is listed (`facing` in pass.glsl), and its unit normal.
// `object`: the G-buffer holds the mesh there (background.comp's test).
bool listed_at(ivec2 p, out vec3 n, out bool object) {
    ivec2 q = min(p, ivec2(pc.size.xy) - 1);
    vec4 N = gbuffer_texel(imageLoad(gnrm, q).x);
    object = N.w > 0.5;
    return facing(q, N, n) && inside(p);
}

// Appends `value` where `take` (one atomic per subgroup: its lanes that take consecutive places).
#define APPEND(list, take, value)                                                     \
    {                                                                                 \
        uvec4 ballot = subgroupBallot(take);                                          \
        uint n = subgroupBallotBitCount(ballot);                                      \
        uint base = 0u;                                                               \
        if (subgroupElect() && n > 0u) {                                              \
            base = atomicAdd(list.count, n);                                          \
            atomicMax(list.groups[0], (base + n + 63u) / 64u);                        \
        }                                                                             \
        base = subgroupBroadcastFirst(base);                                          \
        if (take) list.at[base + subgroupBallotExclusiveBitCount(ballot)] = (value); \
    }

// One invocation a 2 × 2 block: each pixel's G-buffer texel is read once, and its test is the one dot
// product: cheaper than one invocation a pixel, where a block's first pixel reads and tests the
// other three again (with their tangent frames) to choose its representative (docs/renderer.md,
// Alternatives measured and rejected).
// The same lists in another order: the same images, bit for bit.
void main() {
    DiffuseLight d;
    if (!LATER) READ_DIFFUSE_LIGHT(d, sh, lights, pc.params.x != 0u);
    bool diffuse = pc.params.y != 0u;
    ivec2 c = ivec2(gl_GlobalInvocationID.xy);
    ivec2 rep = ivec2(-1);
    bool off_object = false;
    [[unroll]] for (int k = 0; k < 4; k++) {
        ivec2 p = 2 * c + ivec2(k & 1, k >> 1);
        vec3 normal;
        bool object;
        bool listed = listed_at(p, normal, object);
        if (LATER) off_object = off_object || (inside(p) && !object);
        if (!LATER && inside(p)) {
            vec4 acc = vec4(0.0, 0.0, 0.0, 1.0);
            if (!object) acc = vec4(textureLod(env_tex, equirect_uv(camera_ray(p)), backdrop_lod()).rgb, 0.0);
            if (!LATER && diffuse && listed) acc.rgb += pc.fparams.rgb / PI * diffuse_irradiance(d, normal);
            imageStore(accum, p, acc);
        }
        if (PIXELS) APPEND(pixels, listed, uint(p.x) | (uint(p.y) << 16));
        if (listed && rep.x < 0) rep = p;
    }
    // The block's first listed pixel, in the order (0, 0), (1, 0), (0, 1), (1, 1).
    APPEND(blocks, rep.x >= 0, uint(rep.x) | (uint(rep.y) << 16));
    if (LATER) APPEND(background, off_object, uint(2 * c.x) | (uint(2 * c.y) << 16));
}

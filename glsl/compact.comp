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
#include "pass.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) readonly uniform image2D gnrm;
// count, then groups (x, y, z) (the header written as (0, 0, 1, 1) before this pass), then x | y << 16.
layout(std430, set = 0, binding = 1) buffer Pixels { uint count; uint groups[3]; uint at[]; } pixels;
// The same for the 2 × 2 blocks of pixels with any pixel listed, each by its first listed pixel
// (in the order (0, 0), (1, 0), (0, 1), (1, 1)): the pixel whose samples a sparse filtered lobe
// pass takes for the block (`denoise::sparse`).
layout(std430, set = 0, binding = 2) buffer Blocks { uint count; uint groups[3]; uint at[]; } blocks;
// Every pixel's shading normal, alpha 1 where listed (0 elsewhere): what the sparse filter reads.
layout(set = 0, binding = 3, rgba32f) writeonly uniform image2D normals;

bool listed_at(ivec2 p, out vec3 n) {
    vec3 wo;
    Frame f;
    ivec2 q = min(p, ivec2(pc.size.xy) - 1);
    bool listed = inside(p) && shaded(q, imageLoad(gnrm, q), f, wo);
    n = f.n;
    return listed;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    vec3 normal;
    bool listed = listed_at(p, normal);
    if (inside(p)) imageStore(normals, p, vec4(normal, listed ? 1.0 : 0.0));
    // One atomic per subgroup: its listed lanes take consecutive places.
    uvec4 ballot = subgroupBallot(listed);
    uint n = subgroupBallotBitCount(ballot);
    uint base = 0u;
    if (subgroupElect() && n > 0u) {
        base = atomicAdd(pixels.count, n);
        atomicMax(pixels.groups[0], (base + n + 63u) / 64u);
    }
    base = subgroupBroadcastFirst(base);
    if (listed) pixels.at[base + subgroupBallotExclusiveBitCount(ballot)] = uint(p.x) | (uint(p.y) << 16);

    // The block of which p is the first pixel (p even): its representative.
    ivec2 rep = ivec2(-1);
    if ((p.x & 1) == 0 && (p.y & 1) == 0) {
        for (int k = 3; k >= 0; k--) {
            ivec2 r = p + ivec2(k & 1, k >> 1);
            vec3 unused;
            if (k == 0 ? listed : listed_at(r, unused)) rep = r;
        }
    }
    bool block = rep.x >= 0;
    ballot = subgroupBallot(block);
    n = subgroupBallotBitCount(ballot);
    base = 0u;
    if (subgroupElect() && n > 0u) {
        base = atomicAdd(blocks.count, n);
        atomicMax(blocks.groups[0], (base + n + 63u) / 64u);
    }
    base = subgroupBroadcastFirst(base);
    if (block) blocks.at[base + subgroupBallotExclusiveBitCount(ballot)] = uint(rep.x) | (uint(rep.y) << 16);
}

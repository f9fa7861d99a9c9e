#version 460
// Starts the accumulation image: the environment (at the backdrop's mip level, `backdrop_lod`)
// behind the object with alpha 0, and
// (0, 0, 0, 1) on the object, where the shading passes add their terms.
//
// BLOCKS (a frame that rasterises and filters sparsely, `compact::Start::Later`): the image was
// cleared to (0, 0, 0, 1), and the pass runs over the list of 2 × 2 blocks with a pixel off the
// object that `compact.comp` wrote (each by its top-left pixel), storing the environment at those
// pixels alone: on llvmpipe a texture lookup runs for every lane of a vector whatever its mask, so
// over the whole image it would run at every pixel, three quarters of them on the object, and the
// compact pass's lookups over the image cost more than this pass over the blocks (docs/renderer.md,
// Alternatives measured and rejected). The same arithmetic, so the same image bit for bit.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#define PIXELS_BINDING 3
#include "pass.glsl"
layout(constant_id = 0) const bool BLOCKS = false;
// Over the image in groups of 8 × 8, or (BLOCKS) over the list in groups of 64: the same size.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, r32ui) readonly uniform uimage2D gnrm;  // gbuffer_code
layout(set = 0, binding = 1, rgba32f) writeonly uniform image2D accum;
layout(set = 0, binding = 2) uniform sampler2D env_tex;

vec4 background(ivec2 p) { return vec4(textureLod(env_tex, equirect_uv(camera_ray(p)), backdrop_lod()).rgb, 0.0); }

void main() {
    if (BLOCKS) {
        // The list's entry of this invocation: x + 8 y within the group, as `listed_pixel` reads a
        // one-dimensional group of 64.
        ivec2 corner;
        uint i = gl_WorkGroupID.x * 64u + gl_LocalInvocationIndex;
        uint count = pixels.count;
        uint packed = pixels.at[min(i, max(count, 1u) - 1u)];
        corner = ivec2(packed & 0xffffu, packed >> 16);
        if (i >= count) return;
        [[unroll]] for (int k = 0; k < 4; k++) {
            ivec2 p = corner + ivec2(k & 1, k >> 1);
            ivec2 q = min(p, ivec2(pc.size.xy) - 1);
            if (inside(p) && imageLoad(gnrm, q).x == 0u) imageStore(accum, p, background(p));
        }
        return;
    }
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!inside(p)) return;
    if (imageLoad(gnrm, p).x != 0u) {
        imageStore(accum, p, vec4(0.0, 0.0, 0.0, 1.0));
    } else {
        imageStore(accum, p, background(p));
    }
}

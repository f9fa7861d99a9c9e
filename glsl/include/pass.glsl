// The push constants every compute pass shares (128 bytes, the guaranteed minimum), and the
// G-buffer access of the mesh passes.
//
// Loops and branches on llvmpipe (Mesa 22.3, the machine every test runs on), which shape these
// shaders: an `if` is an execution mask and no branch (`lp_bld_nir_soa.c` `if_cond`), so both of
// its sides run for every 8-lane vector, masked, whatever its lanes take, even where the condition
// is the same for the whole dispatch (a push constant); an early `return` only masks what follows.
// (Some operations cost less under a mask: image, texel and storage-buffer accesses go lane by
// lane there and skip masked lanes.) Code a dispatch does not need must go by a specialisation
// constant (lobe.comp's OUTPUT) or by dispatching over a list of the pixels that need
// it (compact.comp). A loop is the one real branch: its body always runs once, and it goes round
// again while any lane is still active (a loop under a condition false everywhere costs one masked
// round, a small part of taking it). So a `for (i < n)` loop costs n + 1 bodies (the last runs
// only to find every lane done), and the sample loops here
// are do-while loops where the count is known to be at least 1 (lobe passes at 8 spp: 2 bodies
// instead of 3, identical images). Code that only some samples need costs its full price in every
// sample unless it moves out of the sample loop into a loop of its own, which runs one masked
// round for a vector that needs none of it (lobe.comp's `light_hits`).
#ifndef PASS_GLSL
#define PASS_GLSL
#include "common.glsl"

#ifdef LOBE_PASS
// The lobe pass's own (`gpu::LobePush`): the frame's first 80 bytes, then the lobe's.
layout(push_constant) uniform Push {
    vec4 eye;
    vec4 right;
    vec4 up;
    vec4 forward;
    uvec4 size;
    uvec4 params;       // lobe index, samples per lobe N, seed of the frame, points in the light set
    uint mode;          // where the pass writes (`plan::Output`): 0 accum, 1 rough, 2 cells, 3 cells with the light term per pixel
    float lod_bias;     // the residual's lod bias (`key`)
    vec2 light_counts;  // the bright and the dark light-sample set's sample counts
    uvec4 ends;         // each light's end in the light set (tiles, strips, the reach test)
} pc;
#else
layout(push_constant) uniform Push {
    vec4 eye;      // camera position
    vec4 right;    // camera right · tan(fov/2) · aspect
    vec4 up;       // camera up · tan(fov/2)
    vec4 forward;  // camera forward (unit)
    uvec4 size;    // image W, H; environment W, H
    uvec4 params;  // lobe index, samples per lobe N, first sample of this dispatch, total samples
    vec4 fparams;  // diffuse rgb (diffuse) | 1/(total samples) (mis) | 1/σ² (denoise)
    vec4 light;    // canvas light direction, intensity
} pc;
#endif

// The primary ray through the centre of pixel p (the mesh camera, docs/model.md, Frames and conventions).
vec3 camera_ray(ivec2 p) {
    vec2 ndc = (vec2(p) + 0.5) / vec2(pc.size.xy) * 2.0 - 1.0;
    return normalize(pc.forward.xyz + ndc.x * pc.right.xyz - ndc.y * pc.up.xyz);
}

// The mip level of the environment the mesh view's backdrop shows (`Settings::backdrop_blur`): 0
// the map itself. It travels in the forward vector's unused fourth component.
float backdrop_lod() { return pc.forward.w; }

bool inside(ivec2 p) { return p.x < int(pc.size.x) && p.y < int(pc.size.y); }

// Whether a G-buffer texel N (`gbuffer_texel`: the normal, alpha 1 marking the object) holds the
// mesh facing the eye, with its shading frame and ω_o (local): the pixels `compact.comp` lists and
// the mesh passes shade. ω_o is the reverse of the pixel's camera ray, on which the surface point
// lies (the G-buffer keeps no position: one image load a pixel instead of two, and less
// rasterising on llvmpipe).
bool shaded(ivec2 p, vec4 N, out Frame f, out vec3 wo) {
    f = frame_from_normal(normalize(N.xyz));
    wo = to_local(f, -camera_ray(p));
    return N.w >= 0.5 && wo.z > 0.0;
}

// Whether the G-buffer texel N at pixel q holds the mesh facing the eye, and its unit normal: the
// test of `shaded` without the tangent frame (its ω_o.z is this same dot product), which
// `compact.comp` lists by and the sparse filter (`denoise_sparse.comp`) takes again. The two agree
// where the compiler rounds this same code alike in both (llvmpipe does: the images are the same
// bit for bit); a driver that fused it differently could disagree only where the dot product is
// within rounding of 0, at the silhouette.
bool facing(ivec2 q, vec4 N, out vec3 n) {
    n = normalize(N.xyz);
    return N.w >= 0.5 && dot(-camera_ray(q), n) > 0.0;
}

#ifdef PIXELS_BINDING
// The list `compact.comp` made, dispatched over in groups of 64 (`Recording::dispatch_listed`).
layout(std430, set = 0, binding = PIXELS_BINDING) readonly buffer Pixels { uint count; uint groups[3]; uint at[]; } pixels;

// This invocation's pixel of the list; false past its end.
bool listed_pixel(out ivec2 p) {
    uint count = pixels.count;
    uint i = gl_GlobalInvocationID.x;
    uint packed = pixels.at[min(i, max(count, 1u) - 1u)];
    p = ivec2(packed & 0xffffu, packed >> 16);
    return i < count;
}
#endif

#endif

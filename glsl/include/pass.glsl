// The push constants every compute pass shares (128 bytes, the guaranteed minimum), and the
// G-buffer access of the mesh passes.
#ifndef PASS_GLSL
#define PASS_GLSL
#include "common.glsl"

layout(push_constant) uniform Push {
    vec4 eye;      // camera position
    vec4 right;    // camera right · tan(fov/2) · aspect
    vec4 up;       // camera up · tan(fov/2)
    vec4 forward;  // camera forward (unit)
    uvec4 size;    // image W, H; environment W, H
    uvec4 params;  // lobe index, samples per lobe N, first sample of this dispatch, total samples
    vec4 fparams;  // diffuse rgb (diffuse pass) | 1/(total samples) (mis)
    vec4 light;    // canvas light direction, intensity
} pc;

// The primary ray through the centre of pixel p (SPEC §1 mesh camera).
vec3 camera_ray(ivec2 p) {
    vec2 ndc = (vec2(p) + 0.5) / vec2(pc.size.xy) * 2.0 - 1.0;
    return normalize(pc.forward.xyz + ndc.x * pc.right.xyz - ndc.y * pc.up.xyz);
}

bool inside(ivec2 p) { return p.x < int(pc.size.x) && p.y < int(pc.size.y); }

#endif

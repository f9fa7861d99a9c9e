#version 460
// The canvas pass (docs/model.md, Frames and conventions): a unit sphere seen orthographically down −z, lit by a point
// light at infinity: radiance f(L, ω_o) max(n·L, 0) I per pixel, ω_o = +z; alpha 1 on the sphere, 0 off it.
#extension GL_GOOGLE_include_directive : require
#include "pass.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) writeonly uniform image2D accum;
#define MATERIAL_BINDING 1
#define TABLES_BINDING 2
#include "material.glsl"

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!inside(p)) return;
    vec2 c = (vec2(p) + 0.5) / vec2(pc.size.xy);
    float x = 2.0 * c.x - 1.0, y = 1.0 - 2.0 * c.y;
    float r2 = x * x + y * y;
    if (!(r2 < 1.0)) {
        imageStore(accum, p, vec4(0.0));
        return;
    }
    vec3 n = vec3(x, y, sqrt(1.0 - r2));
    vec3 L = pc.light.xyz;
    float nl = dot(n, L);
    vec3 radiance = vec3(0.0);
    if (nl > 0.0) {
        Frame f = frame_from_normal(n);
        radiance = material_eval(to_local(f, L), to_local(f, vec3(0.0, 0.0, 1.0))) * nl * pc.light.w;
    }
    imageStore(accum, p, vec4(radiance, 1.0));
}

#version 460
// Starts the accumulation image: the environment (level 0) behind the object with alpha 0, and
// (0, 0, 0, 1) on the object, where the shading passes add their terms.
#extension GL_GOOGLE_include_directive : require
#include "pass.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) readonly uniform image2D gnrm;
layout(set = 0, binding = 1, rgba32f) writeonly uniform image2D accum;
layout(set = 0, binding = 2) uniform sampler2D env_tex;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!inside(p)) return;
    if (imageLoad(gnrm, p).w > 0.5) {
        imageStore(accum, p, vec4(0.0, 0.0, 0.0, 1.0));
    } else {
        imageStore(accum, p, vec4(textureLod(env_tex, equirect_uv(camera_ray(p)), 0.0).rgb, 0.0));
    }
}

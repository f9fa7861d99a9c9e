#version 460
// Zeroes one or two RGBA32F images of one size: the sparse filter's cells (and their lights) or the
// rough lobes' image, on devices whose frame plan zeroes them with a compute pass rather than a
// transfer clear (src/render/plan.rs).
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) writeonly uniform image2D first;
layout(set = 0, binding = 1, rgba32f) writeonly uniform image2D second;
layout(push_constant) uniform Push {
    uvec4 size;    // W, H, 1 to zero the second image too
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(pc.size.x) || p.y >= int(pc.size.y)) return;
    imageStore(first, p, vec4(0.0));
    if (pc.size.z != 0u) imageStore(second, p, vec4(0.0));
}

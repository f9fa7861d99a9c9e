#version 460
// Progressive refinement on the GPU: adds this frame's estimate (the accumulation image, a mean over
// its samples) times its sample count into the running sum, or starts the sum with it. The mean is
// the sum over the samples of every frame (compose), so frames may add different counts.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) readonly uniform image2D frame;
layout(set = 0, binding = 1, rgba32f) uniform image2D sum;
layout(push_constant) uniform Push {
    uvec4 size;    // W, H, 1 to start the sum, 0 to add
    vec4 weight;   // x: this frame's sample count
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(pc.size.x) || p.y >= int(pc.size.y)) return;
    vec4 v = imageLoad(frame, p) * pc.weight.x;
    if (pc.size.z == 0u) v += imageLoad(sum, p);
    imageStore(sum, p, v);
}

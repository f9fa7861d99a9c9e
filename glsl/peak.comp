#version 460
// The device's arithmetic peak as `bench` measures it: every invocation runs `iterations` rounds of
// 4 × 8 vec4 fused multiply-adds on 8 independent chains (2 flops a lane each, 256 a round),
// then writes their sum so that nothing is optimised away. flops = invocations × iterations × 256.
// Chosen as the fastest on lavapipe (256-bit registers, 8 invocations each) of the chain counts and
// unrollings tried, and fma() rather than `a * m + c`, which runs far slower there (docs/renderer.md,
// Alternatives measured and rejected). A GPU hides the latency across invocations and needs none
// of this.
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) writeonly buffer Out { vec4 v[]; } result;
layout(push_constant) uniform Push { uint iterations; float m; float c; } pc;

void main() {
    vec4 a0 = vec4(float(gl_GlobalInvocationID.x) * 1e-6);
    vec4 a1 = a0 + 0.1, a2 = a0 + 0.2, a3 = a0 + 0.3, a4 = a0 + 0.4, a5 = a0 + 0.5, a6 = a0 + 0.6, a7 = a0 + 0.7;
    vec4 m = vec4(pc.m), c = vec4(pc.c);
    for (uint i = 0u; i < pc.iterations; i++) {
        a0 = fma(a0, m, c); a1 = fma(a1, m, c); a2 = fma(a2, m, c); a3 = fma(a3, m, c); a4 = fma(a4, m, c); a5 = fma(a5, m, c); a6 = fma(a6, m, c); a7 = fma(a7, m, c);
        a0 = fma(a0, m, c); a1 = fma(a1, m, c); a2 = fma(a2, m, c); a3 = fma(a3, m, c); a4 = fma(a4, m, c); a5 = fma(a5, m, c); a6 = fma(a6, m, c); a7 = fma(a7, m, c);
        a0 = fma(a0, m, c); a1 = fma(a1, m, c); a2 = fma(a2, m, c); a3 = fma(a3, m, c); a4 = fma(a4, m, c); a5 = fma(a5, m, c); a6 = fma(a6, m, c); a7 = fma(a7, m, c);
        a0 = fma(a0, m, c); a1 = fma(a1, m, c); a2 = fma(a2, m, c); a3 = fma(a3, m, c); a4 = fma(a4, m, c); a5 = fma(a5, m, c); a6 = fma(a6, m, c); a7 = fma(a7, m, c);
    }
    result.v[(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y) & 4095u] = a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7;
}

#version 460
// f(ω_i, ω_o) of the material (with its compensation terms: binding 3, the tables) for a list of
// direction pairs in the local frame, in f32: the GPU side of the stability report's f32-against-f64
// agreement.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Pairs { vec4 v[]; } pairs; // wi, wo per pair
layout(std430, set = 0, binding = 1) writeonly buffer Values { vec4 v[]; } values;
#define MATERIAL_BINDING 2
#define TABLES_BINDING 3
#include "material.glsl"
layout(push_constant) uniform Push { uint count; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    values.v[i] = vec4(material_eval(pairs.v[2u * i].xyz, pairs.v[2u * i + 1u].xyz), 0.0);
}

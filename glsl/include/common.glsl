// Shared by every pass: constants, quaternions, the shading frame and equirect mapping of docs/model.md, Frames and
// conventions.
#ifndef COMMON_GLSL
#define COMMON_GLSL

#include "math.glsl"

// docs/model.md, Frames and conventions: t = normalize(Y × n), or (1,0,0) made orthogonal to n where |Y × n| < 1e-6; b
// = n × t.
struct Frame { vec3 t; vec3 b; vec3 n; };

Frame frame_from_normal(vec3 n) {
    vec3 c = cross(vec3(0.0, 1.0, 0.0), n);
    vec3 t = length(c) < 1e-6 ? normalize(vec3(1.0, 0.0, 0.0) - n.x * n) : normalize(c);
    return Frame(t, cross(n, t), n);
}

vec3 to_local(Frame f, vec3 v) { return vec3(dot(v, f.t), dot(v, f.b), dot(v, f.n)); }
vec3 to_world(Frame f, vec3 v) { return v.x * f.t + v.y * f.b + v.z * f.n; }

// Equirect mapping (docs/model.md, Frames and conventions): u = fract(atan2(d.x, −d.z) / 2π), v = acos(d.y) / π.
vec2 equirect_uv(vec3 d) {
    float u = atan(d.x, -d.z) / (2.0 * PI);
    return vec2(fract(u), acos(clamp(d.y, -1.0, 1.0)) / PI);
}

vec3 equirect_dir(vec2 uv) {
    float phi = 2.0 * PI * uv.x;
    float theta = PI * uv.y;
    float s = sin(theta);
    return vec3(s * sin(phi), cos(theta), -s * cos(phi));
}

// A 32-bit integer hash (PCG output permutation) for per-pixel sequence rotations.
uint hash_u32(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

float hash_unit(uint v) { return float(hash_u32(v) >> 8) * (1.0 / 16777216.0); }

// The G-buffer texel (`R32_UINT`, 4 bytes a pixel): 0 off the object (the clear value), else the
// octahedral code of the world normal n (any length; a zero normal codes +z), 16 bits a coordinate
// in [0, 65534], the first plus 1 in the low half so that no normal codes 0. Rounding each coordinate
// by at most half a step, 1/65534, turns the decoded normal by at most about 6.5·10⁻⁵ rad (the map
// stretches the rounding by at most about 3: 6.4·10⁻⁵ was the worst of 4·10⁶ random directions).
uint gbuffer_code(vec3 n) {
    float s = abs(n.x) + abs(n.y) + abs(n.z);
    vec2 e = s > 0.0 ? n.xy / s : vec2(0.0);
    if (n.z < 0.0) e = (1.0 - abs(e.yx)) * vec2(e.x >= 0.0 ? 1.0 : -1.0, e.y >= 0.0 ? 1.0 : -1.0);
    uvec2 q = uvec2(round(clamp(e * 0.5 + 0.5, 0.0, 1.0) * 65534.0));
    return (q.x + 1u) | (q.y << 16);
}

// A G-buffer code as the texel the passes take: vec4(normal, 1) on the object (its length between
// 1/√3 and 1: the readers normalise it, `shaded` and `facing` in pass.glsl), vec4(0, 0, 1, 0) off it.
vec4 gbuffer_texel(uint code) {
    vec2 e = vec2(float(max(code & 0xffffu, 1u) - 1u), float(code >> 16)) * (2.0 / 65534.0) - 1.0;
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    vec2 folded = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    n.xy = n.z < 0.0 ? folded : n.xy;
    return code == 0u ? vec4(0.0, 0.0, 1.0, 0.0) : vec4(n, 1.0);
}

#endif

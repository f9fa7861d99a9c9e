// PI and unit quaternions: what the BRDF model (brdf.glsl) and every pass share. Self-contained (no
// includes, no bindings), so `brdf-shop export --format glsl` ships it as it is.
#ifndef MATH_GLSL
#define MATH_GLSL

const float PI = 3.14159265358979;

// Rotates v by the unit quaternion q = (x, y, z, w).
vec3 quat_rotate(vec4 q, vec3 v) {
    vec3 t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

vec4 quat_conjugate(vec4 q) { return vec4(-q.xyz, q.w); }

#endif

// Paper §4 diffuse term: ρ_d/π · E(n), E from the 9 SH coefficients of the environment's irradiance
// (Ramamoorthi & Hanrahan 2001; the coefficients arrive multiplied by Â_l), plus, for the `key`
// estimator, each key light as a distant source, power · max(n·d, 0). diffuse.comp and compact.comp
// (which starts the image of a frame that rasterises) take it from here: the same arithmetic.
#ifndef DIFFUSE_GLSL
#define DIFFUSE_GLSL

vec3 irradiance(vec3 c[9], vec3 n) {
    float x = n.x, y = n.y, z = n.z;
    return c[0] * 0.282095
        + c[1] * (0.488603 * y) + c[2] * (0.488603 * z) + c[3] * (0.488603 * x)
        + c[4] * (1.092548 * x * y) + c[5] * (1.092548 * y * z)
        + c[6] * (0.315392 * (3.0 * z * z - 1.0)) + c[7] * (1.092548 * x * z)
        + c[8] * (0.546274 * (x * x - y * y));
}

// The coefficients and the lights (`with_lights`: the key estimator's; zero power past their count),
// read where no lane is masked off and at constant indices: llvmpipe broadcasts a uniform
// storage-buffer read only there; elsewhere it reads lane by lane, and the pass costs several times
// as much. The lights' table holds 4 lights (`environment::cone_table`); without lights the SH
// coefficients stand in for it (9 vec4,
// as long as the count and the 4 lights: `diffuse::term`).
struct DiffuseLight { vec3 c[9]; vec4 dir[4]; vec4 power[4]; };
#define READ_DIFFUSE_LIGHT(out_d, sh_buffer, lights_buffer, with_lights)                               \
    {                                                                                                  \
        [[unroll]] for (int k = 0; k < 9; k++) out_d.c[k] = sh_buffer.c[k].rgb;                        \
        uint n_ = with_lights ? min(lights_buffer.count.x, 4u) : 0u;                                    \
        [[unroll]] for (uint k = 0u; k < 4u; k++) {                                                    \
            out_d.dir[k] = with_lights ? lights_buffer.v[2u * k] : vec4(0.0);                           \
            out_d.power[k] = with_lights && k < n_ ? lights_buffer.v[2u * k + 1u] : vec4(0.0);          \
        }                                                                                              \
    }

// E(n) with the lights; a loop of constant count, unrolled (a `for (k < n)` loop costs a body more on
// llvmpipe, see pass.glsl), the lights past the count adding zero.
vec3 diffuse_irradiance(DiffuseLight d, vec3 nrm) {
    vec3 e = irradiance(d.c, nrm);
    for (uint k = 0u; k < 4u; k++) e += d.power[k].rgb * max(dot(nrm, d.dir[k].xyz), 0.0);
    return e;
}

#endif

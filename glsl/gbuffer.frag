#version 460
// G-buffer: the interpolated normal in world space, w = 1 marking the object (the clear value's 0
// elsewhere). The passes take ω_o from the pixel's camera ray (`shaded` in pass.glsl), so no
// position is stored: on llvmpipe writing it costs about 5 ms of a 512² frame.
layout(location = 0) in vec3 in_normal;
layout(location = 0) out vec4 out_normal;

void main() {
    out_normal = vec4(in_normal, 1.0);
}

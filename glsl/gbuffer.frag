#version 460
// G-buffer: position and interpolated normal, in world space (w = 1 marks the object in both).
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    out_position = vec4(in_position, 1.0);
    out_normal = vec4(in_normal, 1.0);
}

#version 460
// G-buffer: the world normal per vertex, projected by the camera's view-projection.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 0) out vec3 out_normal;
layout(push_constant) uniform Push { mat4 view_proj; } pc;

void main() {
    out_normal = in_normal;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}

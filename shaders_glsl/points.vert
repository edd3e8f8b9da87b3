#version 450
#extension GL_GOOGLE_include_directive : require
// One-pixel points at the splat centres: the benchmark's floor (no splatting).
#include "frame.glsl"

layout(location = 0) in vec3 in_center;

void main() {
    gl_Position = F.proj * (F.view * vec4(in_center, 1.0));
    gl_PointSize = 1.0;
}

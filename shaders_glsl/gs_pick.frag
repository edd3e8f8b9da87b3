#version 450
#extension GL_GOOGLE_include_directive : require
// Gaussian splatting pick pass: index + 1 of the nearest pickable Gaussian
// whose pick ellipse (GS_PICK_SIGMAS) covers the pixel; depth = its centre's.
#include "gs_common.glsl"

layout(location = 0) flat in vec4 v_center;
layout(location = 1) flat in vec4 v_conic;
layout(location = 2) flat in vec4 v_color;
layout(location = 0) out uint o_index;

void main() {
    vec2 d = gl_FragCoord.xy - v_center.xy;
    float m2 = v_conic.x * d.x * d.x + v_conic.z * d.y * d.y + 2.0 * v_conic.y * d.x * d.y;
    if (m2 > v_conic.w) discard;
    o_index = floatBitsToUint(v_color.w);
}

#version 450
#extension GL_GOOGLE_include_directive : require
// Gaussian splatting draw: one screen-aligned quad per visible Gaussian (in
// draw order), spanning its ellipse of alpha >= floor (MODE 0) or its pick
// ellipse of GS_PICK_SIGMAS (MODE 1; Gaussians below the pick opacity vanish).
#include "gs_common.glsl"

layout(constant_id = 0) const int MODE = 0;
layout(location = 0) flat out vec4 v_center;   // px x, px y, -, opacity
layout(location = 1) flat out vec4 v_conic;    // a, b, c, pick sigmas^2
layout(location = 2) flat out vec4 v_color;    // rgb, index + 1 as bits

void main() {
    uint g = order[gl_InstanceIndex];
    uint b = REC_STRIDE * g;
    vec4 r0 = rec[b + REC_CENTER], r1 = rec[b + REC_CONIC], r2 = rec[b + REC_AXES], r3 = rec[b + REC_COLOR];
    vec2 s = vec2(float(gl_VertexIndex & 1), float((gl_VertexIndex >> 1) & 1)) * 2.0 - 1.0;
    float scale = MODE == 1 ? r1.w : 1.0;
    vec2 px = r0.xy + scale * (s.x * r2.xy + s.y * r2.zw);
    gl_Position = vec4(px / F.viewport.xy * 2.0 - 1.0, r0.z, 1.0);
    if (MODE == 1 && r0.w < F.params.y) gl_Position = vec4(2.0, 2.0, 2.0, 1.0);   // not pickable
    v_center = r0;
    v_conic = vec4(r1.xyz, F.params.z);
    v_color = r3;
}

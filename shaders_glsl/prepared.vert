#version 450
#extension GL_GOOGLE_include_directive : require
// Splat vertex shader of the pre-pass path: fetches the record prepare.comp
// wrote (deformation and screen setup done once per splat) and emits a quad
// (PRIM_MODE 1, 4-vertex strip per instance) or a square point (PRIM_MODE 2,
// side in the record).

#define VARYING out
#include "frame.glsl"
#include "splat_varyings.glsl"

layout(constant_id = 0) const int PRIM_MODE = 1;

layout(push_constant) uniform Push {
    uint n;
} P;

#include "splat_records.glsl"
layout(std430, set = 0, binding = 5) readonly buffer RecA { vec4 recA[]; };
layout(std430, set = 0, binding = 6) readonly buffer RecB { uvec4 recB[]; };

vec3 oct_decode(vec2 e) {
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return normalize(n);
}

void main() {
    uint slot = PRIM_MODE == 2 ? P.n - 1u - uint(gl_InstanceIndex) : uint(gl_InstanceIndex);
    v_ms_cn = recA[RECA_STRIDE * slot + RECA_MS_CN];
    v_mt_tc = recA[RECA_STRIDE * slot + RECA_MT_TC];
    v_mw_r = recA[RECA_STRIDE * slot + RECA_MW_R];
    uvec4 b0 = recB[RECB_STRIDE * slot + RECB_CENTER], b1 = recB[RECB_STRIDE * slot + RECB_PACKED];
    float lp = F.depth_params.w;
    v_center = vec4(uintBitsToFloat(b0.x), uintBitsToFloat(b0.y), 1.0 / (lp * lp), uintBitsToFloat(b0.z));
    v_index = b0.w;
    v_color = vec4(unpackUnorm4x8(b1.z).rgb, 1.0);
    v_normal = vec4(oct_decode(unpackSnorm2x16(b1.w)), 0.0);
    if (PRIM_MODE == 2) {
        gl_PointSize = uintBitsToFloat(b1.x);
        gl_Position = vec4(v_center.xy * 2.0 * F.viewport.zw - 1.0, 0.5, 1.0);
        return;
    }
    vec2 lo = vec2(float(b1.x & 0xFFFFu), float(b1.x >> 16)) * (1.0 / 16.0);   // pixels, 12.4 fixed point
    vec2 hi = vec2(float(b1.y & 0xFFFFu), float(b1.y >> 16)) * (1.0 / 16.0);
    int corner = gl_VertexIndex & 3;
    vec2 f = vec2(float(corner & 1), float(corner >> 1));
    gl_Position = vec4(mix(lo, hi, f) * 2.0 * F.viewport.zw - 1.0, 0.5, 1.0);
}

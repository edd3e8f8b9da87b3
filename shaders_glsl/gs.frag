#version 450
#extension GL_GOOGLE_include_directive : require
// Gaussian splatting: alpha = min(ceiling, opacity exp(-d^T conic d / 2)),
// premultiplied, blended front to back ("under": ONE_MINUS_DST_ALPHA, ONE).
#include "gs_common.glsl"

layout(location = 0) flat in vec4 v_center;
layout(location = 1) flat in vec4 v_conic;
layout(location = 2) flat in vec4 v_color;
layout(location = 0) out vec4 o_color;

void main() {
    vec2 d = gl_FragCoord.xy - v_center.xy;
    float power = -0.5 * (v_conic.x * d.x * d.x + v_conic.z * d.y * d.y) - v_conic.y * d.x * d.y;
    if (power > 0.0) discard;
    float alpha = min(F.params.x, v_center.w * exp(power));
    if (alpha < F.limits.w) discard;
    o_color = vec4(v_color.rgb * alpha, alpha);
}

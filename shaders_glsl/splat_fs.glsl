// Splat fragment shader body; the including file defines SPLAT_PASS:
//   0 visibility (depth only, pushed back by epsilon along the view ray)
//   1 attributes (additive weight*colour, weight*normal/depth, weight)
//   2 picking (splat index + 1, exact depth)
// Ray-splat intersection in eye space through the projective screen->tangent
// mapping; EWA screen-space low-pass approximation r^2 = min(r3d^2, r2d^2)
// (Botsch, Hornung, Zwicker, Kobbelt 2005, "High-Quality Surface Splatting on
// Today's GPUs", Sect. 4); Gaussian weight exp(-k r^2) with cutoff r^2 <= 1.

#define VARYING in
#include "frame.glsl"
#include "splat_varyings.glsl"

#if SPLAT_PASS == 1
layout(location = 0) out vec4 o_color;    // w * linear rgb, w
layout(location = 1) out vec4 o_normal;   // w * normal, w * depth
#elif SPLAT_PASS == 2
layout(location = 0) out uint o_index;
#endif

void main() {
    vec3 P = vec3(gl_FragCoord.xy, 1.0);
    float den = dot(v_mw_r.xyz, P);
    if (abs(den) < 1e-30) den = den < 0.0 ? -1e-30 : 1e-30;
    float s = dot(v_ms_cn.xyz, P) / den;
    float t = dot(v_mt_tc.xyz, P) / den;
    float r3 = s * s + t * t;
    vec2 d2 = gl_FragCoord.xy - v_center.xy;
    float r2 = dot(d2, d2) * v_center.z;
    float r = min(r3, r2);
    if (!(r <= 1.0)) discard;

    float tc = v_mt_tc.w, rad = v_mw_r.w;
    float depth = v_ms_cn.w / den;                       // along the view axis
    if (!(r3 <= 1.0) || !(abs(depth - tc) <= rad)) depth = clamp(depth, tc - rad, tc + rad);
#if SPLAT_PASS == 0
    depth += v_center.w;
#endif
    float near = F.depth_params.x, far = F.depth_params.y;
    if (depth < near || depth > far) discard;
    gl_FragDepth = far / (far - near) * (1.0 - near / depth);

#if SPLAT_PASS == 1
    float w = exp(-F.misc.x * r);
    o_color = vec4(v_color.rgb * w, w);
    o_normal = vec4(v_normal.xyz * w, depth * w);
#elif SPLAT_PASS == 2
    o_index = v_index;
#endif
}

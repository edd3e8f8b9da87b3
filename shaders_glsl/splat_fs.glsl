// Splat fragment shader body; the including file defines SPLAT_PASS:
//   0 visibility (depth only, pushed back by epsilon along the view ray)
//   1 attributes (additive weight*colour, weight*normal/depth, weight)
//   2 picking (splat index + 1, exact depth)
// The per-pixel test is splat_pixel.glsl (shared with the compute rasterizer).

#define VARYING in
#include "frame.glsl"
#include "splat_varyings.glsl"
#include "splat_pixel.glsl"

#if SPLAT_PASS == 1
layout(location = 0) out vec4 o_color;    // w * linear rgb, w
layout(location = 1) out vec4 o_normal;   // w * normal, w * depth
#elif SPLAT_PASS == 2
layout(location = 0) out uint o_index;
#endif

void main() {
    float r, depth, zwin;
    if (!splat_pixel(gl_FragCoord.xy, v_ms_cn, v_mt_tc, v_mw_r, v_center, SPLAT_PASS == 0, r, depth, zwin))
        discard;
    gl_FragDepth = zwin;

#if SPLAT_PASS == 1
    float w = exp(-F.misc.x * r);
    o_color = vec4(v_color.rgb * w, w);
    o_normal = vec4(v_normal.xyz * w, depth * w);
#elif SPLAT_PASS == 2
    o_index = v_index;
#endif
}

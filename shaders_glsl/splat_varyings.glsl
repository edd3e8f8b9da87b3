// Flat per-splat varyings written by the splat vertex shader and read by every
// splat fragment shader (all of them declare all of them: the interfaces match).
// Pixel P = (gl_FragCoord.xy, 1):  den = dot(mw, P);  s = dot(ms, P) / den;
// t = dot(mt, P) / den;  ray depth along the view axis = cn / den.
layout(location = 0) flat VARYING vec4 v_ms_cn;     // ms, c.n
layout(location = 1) flat VARYING vec4 v_mt_tc;     // mt, depth of the centre along the view axis
layout(location = 2) flat VARYING vec4 v_mw_r;      // mw, splat radius max(|u'|, |v'|)
layout(location = 3) flat VARYING vec4 v_center;    // centre (pixels), 1/lowpass^2, visibility epsilon
layout(location = 4) flat VARYING vec4 v_color;     // linear rgb, unused
layout(location = 5) flat VARYING vec4 v_normal;    // unit eye-space normal facing the viewer, unused
layout(location = 6) flat VARYING uint v_index;     // splat index + 1 (picking)

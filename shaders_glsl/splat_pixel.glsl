// The per-pixel test of an EWA splat, shared by the raster fragment shaders
// (splat_fs.glsl) and the compute rasterizer (splat_cs_raster.glsl).
// Ray-splat intersection in eye space through the projective screen->tangent
// mapping; EWA screen-space low-pass approximation r^2 = min(r3d^2, r2d^2)
// (Botsch, Hornung, Zwicker, Kobbelt 2005, "High-Quality Surface Splatting on
// Today's GPUs", Sect. 4); Gaussian weight exp(-k r^2) with cutoff r^2 <= 1.
// Requires frame.glsl.
//
// fc: pixel centre (pixels); ms_cn, mt_tc, mw_r, center: the splat's record
// (splat_varyings.glsl); push: add the visibility epsilon (center.w) to the
// depth.  Returns false where the splat does not cover the pixel (the
// fragment shader's discard); else r (squared normalised radius), depth
// (along the view axis, eye units) and zwin (the window depth, 0..1, that
// the depth buffer stores).
bool splat_pixel(vec2 fc, vec4 ms_cn, vec4 mt_tc, vec4 mw_r, vec4 center, bool push,
                 out float r, out float depth, out float zwin) {
    r = 2.0; depth = 0.0; zwin = 1.0;
    vec3 P = vec3(fc, 1.0);
    float den = dot(mw_r.xyz, P);
    if (abs(den) < 1e-30) den = den < 0.0 ? -1e-30 : 1e-30;
    float s = dot(ms_cn.xyz, P) / den;
    float t = dot(mt_tc.xyz, P) / den;
    float r3 = s * s + t * t;
    vec2 d2 = fc - center.xy;
    float r2 = dot(d2, d2) * center.z;
    r = min(r3, r2);
    if (!(r <= 1.0)) return false;

    float tc = mt_tc.w, rad = mw_r.w;
    depth = ms_cn.w / den;                               // along the view axis
    if (!(r3 <= 1.0) || !(abs(depth - tc) <= rad)) depth = clamp(depth, tc - rad, tc + rad);
    if (push) depth += center.w;
    float near = F.depth_params.x, far = F.depth_params.y;
    if (depth < near || depth > far) return false;
    zwin = far / (far - near) * (1.0 - near / depth);
    return true;
}

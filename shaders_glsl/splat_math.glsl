// Per-splat math shared by the splat vertex shader (splat_vs.glsl) and the
// compute pre-pass (prepare_cs.glsl).  Requires frame.glsl and deform.glsl.

struct Splat {
    vec4 ms_cn, mt_tc, mw_r;   // screen -> tangent mapping (see splat_varyings.glsl)
    vec4 center;               // centre (pixels), 1/lowpass^2, visibility epsilon
    vec3 color;                // linear rgb with selection tint
    vec3 normal;               // unit eye-space normal facing the viewer
    vec2 lo, hi;               // screen bound (NDC)
    vec2 cc;                   // projected centre (NDC)
    float psize;               // SPLAT_POINT: side of the square point (pixels)
};

const int SPLAT_CULLED = 0;
const int SPLAT_QUAD = 1;
const int SPLAT_POINT = 2;

// p' = p + sum_k B_k dC_k;  J_ij = delta_ij + sum_k dC_k[i] B{j}_k;  u' = J u, v' = J v
// (one group of 4 columns; dp and Jm = J - I accumulate over groups)
#include "rotation.glsl"

void deform_group(int g, vec4 B, vec4 Bx, vec4 By, vec4 Bz, inout vec3 dp, inout mat3 Jm) {
    vec4 dx = D.dC[3 * g], dy = D.dC[3 * g + 1], dz = D.dC[3 * g + 2];
    dp += vec3(dot(B, dx), dot(B, dy), dot(B, dz));
    Jm[0] += vec3(dot(dx, Bx), dot(dy, Bx), dot(dz, Bx));
    Jm[1] += vec3(dot(dx, By), dot(dy, By), dot(dz, By));
    Jm[2] += vec3(dot(dx, Bz), dot(dy, Bz), dot(dz, Bz));
    if (D.rot[4 * g].w != 0.0)             // a rotating handle (rotation-aware mode)
        rotation_blend(D.rot[4 * g], D.rot[4 * g + 1], D.rot[4 * g + 2], D.rot[4 * g + 3], B, Bx, By, Bz, dp, Jm);
}

// Offset of the screen-space extent of the projected ellipse along one axis,
// relative to the projected centre: a' = (U.x - xc U.w, V.x - xc V.w), wxy = (U.w, V.w).
// Tangent lines of the conic h^T diag(1,1,-1) h = 0 (cancellation-free form).
vec2 extent(vec2 ap, vec2 wxy, float cw) {
    float wDw = dot(wxy, wxy) - cw * cw;                  // < 0: ellipse in front of the eye
    float aDw = dot(ap, wxy);
    float cr = ap.x * wxy.y - ap.y * wxy.x;
    float disc = max(dot(ap, ap) * cw * cw - cr * cr, 0.0);
    float sq = sqrt(disc);
    float e0 = (aDw + sq) / wDw, e1 = (aDw - sq) / wDw;
    return vec2(min(e0, e1), max(e0, e1));
}

// Everything a splat needs on screen, from its (deformed) model-space centre
// and axes.  Returns SPLAT_CULLED (outside the frustum, back-facing with
// culling on, degenerate), SPLAT_POINT or SPLAT_QUAD.
// SPLAT_POINT: the footprint (projected ellipse and low-pass disc) lies within
// F.misc.w pixels of the projected centre along x and y and the centre is on
// screen: the splat is drawn as one square POINT_LIST point of side psize
// centred there, which covers every pixel centre the quad would (the fragment
// shader is the same), with one vertex instead of a 4-vertex strip.
int prepare_splat(vec3 p, vec3 u, vec3 v, vec3 srgb, uint flags, out Splat S) {
    S.ms_cn = vec4(0.0); S.mt_tc = vec4(0.0); S.mw_r = vec4(0.0); S.center = vec4(0.0);
    S.color = vec3(0.0); S.normal = vec3(0.0); S.lo = vec2(0.0); S.hi = vec2(0.0); S.cc = vec2(0.0);
    S.psize = 1.0;
    mat3 R3 = mat3(F.view);
    vec3 c = (F.view * vec4(p, 1.0)).xyz;
    vec3 ue = R3 * (u * F.display.x), ve = R3 * (v * F.display.x);   // display: splat size scale
    vec3 nraw = cross(ue, ve);
    float area = length(nraw);
    float rad = max(length(ue), length(ve));
    if (!(area > 0.0)) return SPLAT_CULLED;
    vec3 n = nraw / area;
    float cn = dot(c, n);
    if (F.options.x != 0u && cn > 0.0) return SPLAT_CULLED;   // back-facing

    float near = F.depth_params.x, far = F.depth_params.y;
    vec4 U = F.proj * vec4(ue, 0.0), V = F.proj * vec4(ve, 0.0), C = F.proj * vec4(c, 1.0);
    vec2 wxy = vec2(U.w, V.w);
    float wr = length(wxy);
    if (C.w + wr < near || C.w - wr > far) return SPLAT_CULLED;   // in front of near / beyond far

    vec2 px_ndc = 2.0 * F.viewport.zw;                   // one pixel in NDC
    float lp = F.depth_params.w;
    bool small = false;
    if (C.w - wr < near * 1.001) {
        S.lo = vec2(-1.0); S.hi = vec2(1.0);             // crosses the near plane: full viewport
    } else {
        vec2 cc = C.xy / C.w;
        vec2 ex = extent(vec2(U.x - cc.x * U.w, V.x - cc.x * V.w), wxy, C.w);
        vec2 ey = extent(vec2(U.y - cc.y * U.w, V.y - cc.y * V.w), wxy, C.w);
        vec2 lpr = lp * px_ndc;
        // exact bound of the ellipse and the low-pass disc; fragments are
        // sampled at pixel centres, so only a rounding margin is needed
        vec2 lo = cc + min(vec2(ex.x, ey.x), -lpr) - 0.02 * px_ndc;
        vec2 hi = cc + max(vec2(ex.y, ey.y), lpr) + 0.02 * px_ndc;
        if (any(greaterThan(lo, vec2(1.0))) || any(lessThan(hi, vec2(-1.0)))) return SPLAT_CULLED;
        S.lo = max(lo, vec2(-1.0) - px_ndc);
        S.hi = min(hi, vec2(1.0) + px_ndc);
        // largest distance of the footprint from the centre along x, y (pixels)
        vec2 he = max(vec2(max(-ex.x, ex.y), max(-ey.x, ey.y)) * 0.5 * F.viewport.xy, vec2(lp)) + 0.02;
        float h = max(he.x, he.y);
        // (beyond 1 pixel only for round-ish footprints: a square around an
        // elongated one would shade many more pixels than its quad)
        small = h <= F.misc.w && (h <= 1.0 || 2.0 * min(he.x, he.y) >= h)
                && all(lessThan(abs(cc), vec2(1.0)));
        S.psize = ceil(16.0 * h) * 0.125;                  // 2 h rounded up to the point-size granularity
    }
    S.cc = C.xy / C.w;

    vec3 ud = cross(ve, n) / area, vd = cross(n, ue) / area;   // dual basis: ud.ue = 1, ud.ve = 0
    vec3 As = cn * ud - dot(ud, c) * n;
    vec3 At = cn * vd - dot(vd, c) * n;
    float D00 = F.pix_to_ray.x, D02 = F.pix_to_ray.y, D11 = F.pix_to_ray.z, D12 = F.pix_to_ray.w;
    S.ms_cn = vec4(D00 * As.x, D11 * As.y, D02 * As.x + D12 * As.y - As.z, cn);
    S.mt_tc = vec4(D00 * At.x, D11 * At.y, D02 * At.x + D12 * At.y - At.z, -c.z);
    S.mw_r = vec4(D00 * n.x, D11 * n.y, D02 * n.x + D12 * n.y - n.z, rad);
    vec2 cpx = (S.cc * 0.5 + 0.5) * F.viewport.xy;
    S.center = vec4(cpx, 1.0 / (lp * lp), F.depth_params.z * rad);

    vec3 col = pow(F.display.y >= 0.0 ? vec3(F.display.y) : srgb, vec3(2.2));   // grey shading mode
    if ((flags & FLAG_SUPPORT) != 0u) col = mix(col, F.tint_support.rgb, F.tint_support.a);
    if ((flags & FLAG_HANDLE) != 0u) col = mix(col, F.tint_handle.rgb, F.tint_handle.a);
    if ((flags & FLAG_INACTIVE) != 0u) col *= 0.35;
    S.color = col;
    // a splat seen from behind (culling off) is shaded facing the eye: its normal mirrored in
    // the plane across the view ray (only the component along the ray flips; the headlight's
    // diffuse and specular terms equal those of -n).  Negating it would also turn the sideways
    // part: at a silhouette a back rim splat (n ~ sideways) then blends with the front rim's
    // into a normal facing the eye, a bright fringe.
    vec3 ray = normalize(c);
    S.normal = cn > 0.0 ? n - 2.0 * dot(n, ray) * ray : n;
    return small ? SPLAT_POINT : SPLAT_QUAD;
}

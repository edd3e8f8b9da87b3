// Splat vertex shader body (included by splat.vert / splat_k8.vert, which
// define BASIS_GROUPS = number of 4-column groups of the deformation basis).
//
// Per instance: centre p, tangent semi-axes u, v, colour, flags and the basis
// rows B, Bx, By, Bz (one vec4 each per group of 4 columns).  Per frame: dC in
// push constants as rows dC[3g + i] = (dC_{4g..4g+3})[i], i = x, y, z.
//   p' = p + sum_k B_k dC_k
//   J  = I + sum_k dC_k (Bx_k, By_k, Bz_k)^T,  i.e.  J_ij = delta_ij + sum_k dC_k[i] B{j}_k
//   u' = J u,  v' = J v            (Botsch & Kobbelt 2005, Sect. 6-7)
// Emits a screen-space quad (4-vertex triangle strip per instance) bounding
// the projected ellipse and the low-pass disc; culls splats outside the view
// frustum, behind the near plane and (optionally) back-facing ones.

#define VARYING out
#include "frame.glsl"
#include "splat_varyings.glsl"

layout(location = 0) in vec3 in_center;
layout(location = 1) in vec3 in_u;
layout(location = 2) in vec3 in_v;
layout(location = 3) in vec4 in_color;      // sRGB unorm8x4
layout(location = 4) in uint in_flags;
layout(location = 5) in vec4 in_basis[4 * BASIS_GROUPS];  // per group: B, Bx, By, Bz

layout(push_constant) uniform Push {
    vec4 dC[3 * BASIS_GROUPS];
} P;

void cull() {
    gl_Position = vec4(-4.0, -4.0, 0.5, 1.0);   // all four corners equal: zero-area, off screen
    v_ms_cn = vec4(0.0); v_mt_tc = vec4(0.0); v_mw_r = vec4(0.0); v_center = vec4(0.0);
    v_color = vec4(0.0); v_normal = vec4(0.0); v_index = 0u;
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

void main() {
    vec3 p = in_center, u = in_u, v = in_v;
    uint flags = in_flags;
    if ((flags & FLAG_DEFORMED) != 0u) {
        vec3 dp = vec3(0.0);
        mat3 Jm = mat3(0.0);                              // J - I
        for (int g = 0; g < BASIS_GROUPS; ++g) {
            vec4 B = in_basis[4 * g], Bx = in_basis[4 * g + 1];
            vec4 By = in_basis[4 * g + 2], Bz = in_basis[4 * g + 3];
            vec4 dx = P.dC[3 * g], dy = P.dC[3 * g + 1], dz = P.dC[3 * g + 2];
            dp += vec3(dot(B, dx), dot(B, dy), dot(B, dz));
            Jm[0] += vec3(dot(dx, Bx), dot(dy, Bx), dot(dz, Bx));
            Jm[1] += vec3(dot(dx, By), dot(dy, By), dot(dz, By));
            Jm[2] += vec3(dot(dx, Bz), dot(dy, Bz), dot(dz, Bz));
        }
        p += dp;
        u += Jm * u;
        v += Jm * v;
    }

    mat3 R3 = mat3(F.view);
    vec3 c = (F.view * vec4(p, 1.0)).xyz;
    vec3 ue = R3 * u, ve = R3 * v;
    vec3 nraw = cross(ue, ve);
    float area = length(nraw);
    float rad = max(length(ue), length(ve));
    if (!(area > 0.0)) { cull(); return; }
    vec3 n = nraw / area;
    float cn = dot(c, n);
    if (F.options.x != 0u && cn > 0.0) { cull(); return; }   // back-facing

    float near = F.depth_params.x, far = F.depth_params.y;
    vec4 U = F.proj * vec4(ue, 0.0), V = F.proj * vec4(ve, 0.0), C = F.proj * vec4(c, 1.0);
    vec2 wxy = vec2(U.w, V.w);
    float wr = length(wxy);
    if (C.w + wr < near || C.w - wr > far) { cull(); return; }   // entirely in front of near / beyond far

    vec2 lo, hi;
    vec2 px_ndc = 2.0 * F.viewport.zw;                   // one pixel in NDC
    float lp = F.depth_params.w;
    if (C.w - wr < near * 1.001) {
        lo = vec2(-1.0); hi = vec2(1.0);                 // crosses the near plane: full viewport
    } else {
        vec2 cc = C.xy / C.w;
        vec2 ex = extent(vec2(U.x - cc.x * U.w, V.x - cc.x * V.w), wxy, C.w);
        vec2 ey = extent(vec2(U.y - cc.y * U.w, V.y - cc.y * V.w), wxy, C.w);
        vec2 lpr = lp * px_ndc;
        lo = cc + min(vec2(ex.x, ey.x), -lpr) - px_ndc;
        hi = cc + max(vec2(ex.y, ey.y), lpr) + px_ndc;
        if (any(greaterThan(lo, vec2(1.0))) || any(lessThan(hi, vec2(-1.0)))) { cull(); return; }
        lo = max(lo, vec2(-1.0) - px_ndc);
        hi = min(hi, vec2(1.0) + px_ndc);
    }

    // screen -> tangent-plane mapping (see splat_varyings.glsl)
    vec3 ud = cross(ve, n) / area, vd = cross(n, ue) / area;   // dual basis: ud.ue = 1, ud.ve = 0
    vec3 As = cn * ud - dot(ud, c) * n;
    vec3 At = cn * vd - dot(vd, c) * n;
    float D00 = F.pix_to_ray.x, D02 = F.pix_to_ray.y, D11 = F.pix_to_ray.z, D12 = F.pix_to_ray.w;
    v_ms_cn = vec4(D00 * As.x, D11 * As.y, D02 * As.x + D12 * As.y - As.z, cn);
    v_mt_tc = vec4(D00 * At.x, D11 * At.y, D02 * At.x + D12 * At.y - At.z, -c.z);
    v_mw_r = vec4(D00 * n.x, D11 * n.y, D02 * n.x + D12 * n.y - n.z, rad);
    vec2 cpx = (C.xy / C.w * 0.5 + 0.5) * F.viewport.xy;
    v_center = vec4(cpx, 1.0 / (lp * lp), F.depth_params.z * rad);

    vec3 col = pow(in_color.rgb, vec3(2.2));
    if ((flags & FLAG_SUPPORT) != 0u) col = mix(col, F.tint_support.rgb, F.tint_support.a);
    if ((flags & FLAG_HANDLE) != 0u) col = mix(col, F.tint_handle.rgb, F.tint_handle.a);
    v_color = vec4(col, 1.0);
    v_normal = vec4(cn > 0.0 ? -n : n, 0.0);
    v_index = uint(gl_InstanceIndex) + 1u;

    int corner = gl_VertexIndex & 3;
    vec2 f = vec2(float(corner & 1), float(corner >> 1));
    gl_Position = vec4(mix(lo, hi, f), 0.5, 1.0);
}

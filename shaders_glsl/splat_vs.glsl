// Splat vertex shader body (included by splat.vert / splat_k8.vert /
// splat_k12.vert / splat_k16.vert, which define BASIS_GROUPS = number of
// 4-column groups of the deformation basis, zero-padded).
//
// Per instance: centre p, tangent semi-axes u, v, colour, flags and the basis
// rows B, Bx, By, Bz (one vec4 each per group of 4 columns; at most 16 vertex
// attributes for 16 columns, 21 in all: lavapipe has maxVertexInputAttributes
// = 32).  Per frame: dC in the Deform uniform block (deform.glsl, binding 1).
//   p' = p + sum_k B_k dC_k
//   J  = I + sum_k dC_k (Bx_k, By_k, Bz_k)^T,  i.e.  J_ij = delta_ij + sum_k dC_k[i] B{j}_k
//   u' = J u,  v' = J v            (Botsch & Kobbelt 2005, Sect. 6-7)
// Emits a screen-space quad (4-vertex triangle strip per instance) bounding
// the projected ellipse and the low-pass disc; culls splats outside the view
// frustum, behind the near plane and (optionally) back-facing ones.

#define VARYING out
#include "frame.glsl"
#include "splat_varyings.glsl"
#define DEFORM_BINDING 1
#include "deform.glsl"

layout(location = 0) in vec3 in_center;
layout(location = 1) in vec3 in_u;
layout(location = 2) in vec3 in_v;
layout(location = 3) in vec4 in_color;      // sRGB unorm8x4
layout(location = 4) in uint in_flags;
layout(location = 5) in vec4 in_basis[int(BASIS_STRIDE) * BASIS_GROUPS];  // per group: B, Bx, By, Bz

// 0: every splat as a quad; 1: only the SPLAT_QUAD ones (see prepare_splat);
// 2: only the SPLAT_POINT ones, as square points (POINT_LIST).  Modes 1 + 2
// together draw every splat.
layout(constant_id = 0) const int PRIM_MODE = 0;

void cull() {
    gl_Position = vec4(-4.0, -4.0, 0.5, 1.0);   // all corners equal: zero-area, off screen
    if (PRIM_MODE == 2) gl_PointSize = 1.0;
    v_ms_cn = vec4(0.0); v_mt_tc = vec4(0.0); v_mw_r = vec4(0.0); v_center = vec4(0.0);
    v_color = vec4(0.0); v_normal = vec4(0.0); v_index = 0u;
}

#include "splat_math.glsl"
#include "distortion.glsl"

void main() {
    vec3 p = in_center, u = in_u, v = in_v;
    vec3 u0 = u, v0 = v;
    uint flags = in_flags;
    if ((flags & FLAG_DEFORMED) != 0u) {     // splats outside the support skip this
        vec3 dp = vec3(0.0);
        mat3 Jm = mat3(0.0);                  // J - I
        for (int g = 0; g < BASIS_GROUPS; ++g) {
            uint k = BASIS_STRIDE * uint(g);
            deform_group(g, in_basis[k + BASIS_B], in_basis[k + BASIS_BX], in_basis[k + BASIS_BY],
                         in_basis[k + BASIS_BZ], dp, Jm);
        }
        p += dp;
        u += Jm * u;
        v += Jm * v;
    }
    Splat S;
    int kind = prepare_splat(p, u, v, in_color.rgb, flags, S);
    if (kind == SPLAT_CULLED || (PRIM_MODE == 1 && kind == SPLAT_POINT)
        || (PRIM_MODE == 2 && kind != SPLAT_POINT)) { cull(); return; }
    v_ms_cn = S.ms_cn; v_mt_tc = S.mt_tc; v_mw_r = S.mw_r; v_center = S.center;
    v_color = vec4(S.color, 1.0);
    if (F.options.z == 1u)                    // heat map: the stretch of the same J (distortion.glsl)
        v_color.rgb = heat_encode((flags & FLAG_DEFORMED) != 0u ? splat_stretch(u0, v0, u, v) : 1.0,
                                  in_color.rgb, flags);
    v_normal = vec4(S.normal, 0.0);
    v_index = uint(gl_InstanceIndex) + 1u;
    if (PRIM_MODE == 2) {                     // small splat: square point at its centre
        gl_PointSize = S.psize;
        gl_Position = vec4(S.cc, 0.5, 1.0);
        return;
    }
    int corner = gl_VertexIndex & 3;
    vec2 f = vec2(float(corner & 1), float(corner >> 1));
    gl_Position = vec4(mix(S.lo, S.hi, f), 0.5, 1.0);
}

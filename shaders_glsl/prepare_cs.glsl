// Compute pre-pass (once per splat per frame): deformation, eye transform,
// culling and the screen-space setup of prepare_splat(), written as compact
// records for the two splat passes (drawn by prepared.vert with indirect
// draws): quads fill slots 0.. upwards, square points slots n-1 downwards.
// The including file defines BASIS_GROUPS (and DETAIL for the detail mode).

#include "frame.glsl"
#define DEFORM_BINDING 8
#include "deform.glsl"

layout(local_size_x = 64) in;

shared uint s_count[2];   // quads, points in this workgroup
shared uint s_base[2];

// The dispatch covers splats base .. base + count - 1 (the basis binding is a
// window starting at row base: a 16-column basis takes 256 bytes per splat and
// maxStorageBufferRange is 128 MiB on lavapipe, so large clouds are dispatched
// in chunks). The per-splat bindings (geometry, colours, flags, detail) and the
// records are a window too, of n splats starting at splat wbase (the whole
// cloud when it fits one binding; otherwise the renderer draws window after
// window); base .. base + count - 1 lies inside it. n = record slots.
layout(push_constant) uniform Push {
    uint base;
    uint count;
    uint n;
    uint wbase;
} P;

#include "splat_records.glsl"
layout(std430, set = 0, binding = 1) readonly buffer Geom { float geom[]; };      // GEOM_STRIDE floats per splat, from splat P.wbase
layout(std430, set = 0, binding = 2) readonly buffer Colors { uint colors[]; };   // sRGB rgba8, from splat P.wbase
layout(std430, set = 0, binding = 3) readonly buffer Flags { uint flags[]; };     // from splat P.wbase
layout(std430, set = 0, binding = 4) readonly buffer Basis { vec4 basis[]; };     // BASIS_STRIDE * BASIS_GROUPS per splat, from row P.base
layout(std430, set = 0, binding = 5) writeonly buffer RecA { vec4 recA[]; };      // RECA_STRIDE per slot
layout(std430, set = 0, binding = 6) writeonly buffer RecB { uvec4 recB[]; };     // RECB_STRIDE per slot
layout(std430, set = 0, binding = 7) buffer Draws { uint draws[8]; };             // 2 VkDrawIndirectCommand

#include "splat_math.glsl"
#include "distortion.glsl"
#ifdef DETAIL
#define DETAIL_BINDING 9
#include "detail.glsl"
#endif

// bound corner in pixels, 16.16 -> 12.4 fixed point (1/16 pixel), rounded outwards
uint pack_px(vec2 ndc, float dir) {
    vec2 px = clamp((ndc * 0.5 + 0.5) * F.viewport.xy, vec2(0.0), F.viewport.xy);
    vec2 q = dir < 0.0 ? floor(px * 16.0) : ceil(px * 16.0);
    uvec2 u = uvec2(q);
    return u.x | (u.y << 16);
}

vec2 oct_encode(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 e = n.xy;
    if (n.z < 0.0) e = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return e;
}

void main() {
    uint li = gl_GlobalInvocationID.x;          // row in the basis window
    uint i = P.base + li;                       // splat index (the pick id is i + 1)
    uint w = i - P.wbase;                       // row in the per-splat window, record slot range
    if (w == 0u) { draws[0] = 4u; draws[4] = 1u; }
    int kind = SPLAT_CULLED;
    Splat S;
    if (li < P.count) {
        uint gc = GEOM_STRIDE * w + GEOM_CENTER, gu = GEOM_STRIDE * w + GEOM_U, gv = GEOM_STRIDE * w + GEOM_V;
        vec3 p = vec3(geom[gc], geom[gc + 1u], geom[gc + 2u]);
        vec3 u = vec3(geom[gu], geom[gu + 1u], geom[gu + 2u]);
        vec3 v = vec3(geom[gv], geom[gv + 1u], geom[gv + 2u]);
        uint fl = flags[w];
        vec3 u0 = u, v0 = v;
        if ((fl & FLAG_DEFORMED) != 0u) {     // splats outside the support skip this
            vec3 dp = vec3(0.0);
            mat3 Jm = mat3(0.0);
            uint b = BASIS_STRIDE * uint(BASIS_GROUPS) * li;
            for (int g = 0; g < BASIS_GROUPS; ++g) {
                uint k = b + BASIS_STRIDE * uint(g);
                deform_group(g, basis[k + BASIS_B], basis[k + BASIS_BX], basis[k + BASIS_BY], basis[k + BASIS_BZ],
                             dp, Jm);
            }
#ifdef DETAIL
            detail_attach(detail[w], dp, Jm, p, u, v);
#else
            p += dp;
            u += Jm * u;
            v += Jm * v;
#endif
        }
        vec3 srgb = unpackUnorm4x8(colors[w]).rgb;
        kind = prepare_splat(p, u, v, srgb, fl, S);
        if (F.options.z == 1u)                // heat map: the stretch of the same J (distortion.glsl)
            S.color = heat_encode((fl & FLAG_DEFORMED) != 0u ? splat_stretch(u0, v0, u, v) : 1.0, srgb, fl);
    }
    // workgroup-aggregated slot allocation (one global atomic per workgroup and list)
    if (gl_LocalInvocationIndex == 0u) { s_count[0] = 0u; s_count[1] = 0u; }
    barrier();
    uint local = 0u;
    if (kind == SPLAT_QUAD) local = atomicAdd(s_count[0], 1u);
    else if (kind == SPLAT_POINT) local = atomicAdd(s_count[1], 1u);
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        s_base[0] = s_count[0] > 0u ? atomicAdd(draws[1], s_count[0]) : 0u;
        s_base[1] = s_count[1] > 0u ? atomicAdd(draws[5], s_count[1]) : 0u;
    }
    barrier();
    if (kind == SPLAT_CULLED) return;
    uint slot = kind == SPLAT_QUAD ? s_base[0] + local : P.n - 1u - (s_base[1] + local);
    recA[RECA_STRIDE * slot + RECA_MS_CN] = S.ms_cn;
    recA[RECA_STRIDE * slot + RECA_MT_TC] = S.mt_tc;
    recA[RECA_STRIDE * slot + RECA_MW_R] = S.mw_r;
    vec2 pos = kind == SPLAT_QUAD ? S.lo : S.cc;
    recB[RECB_STRIDE * slot + RECB_CENTER] = uvec4(floatBitsToUint(S.center.x), floatBitsToUint(S.center.y),
                                                   floatBitsToUint(S.center.w), i + 1u);
    recB[RECB_STRIDE * slot + RECB_PACKED] = uvec4(kind == SPLAT_QUAD ? pack_px(S.lo, -1.0) : floatBitsToUint(S.psize),
                                                   kind == SPLAT_QUAD ? pack_px(S.hi, 1.0) : 0u,
                                                   packUnorm4x8(vec4(S.color, 1.0)),
                                                   packSnorm2x16(oct_encode(S.normal)));
}

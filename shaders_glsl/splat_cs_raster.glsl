// Compute rasterizer of EWA splats (the compute path of the splat renderer,
// splatedit/render/splat/compute_raster.py): it draws the pre-pass records
// (prepare_cs.glsl) that the raster path draws with prepared.vert, with the
// same per-pixel test (splat_pixel.glsl).  The including file defines
// CRAST_PASS:
//   0 visibility: depth pushed back by epsilon and the splat index packed in
//     64 bits, (window depth bits << 32) | (index + 1), atomicMin per pixel
//     (Schuetz, Kerbl, Wimmer 2021, "Rendering Point Clouds with Compute
//     Shaders and Vertex Order Optimization"); cleared to all ones;
//   1 attributes: where the unpushed depth is at most the visible depth (the
//     raster path's less_equal test), atomicAdd of w*rgb, w and w*normal,
//     w*depth into two float32 RGBA buffers (VK_EXT_shader_atomic_float).
// Coverage: the pixels whose centres lie in the record's bound (the quad of
// prepared.vert, or the square point), top-left rule; the per-pixel test
// discards the rest.
// Three modes (push constant), dispatched in turn: 0 one invocation per
// record slot; a splat whose bound holds more than P.big_pixels pixels is
// appended to a list instead; 1 binning: the listed splats into per-tile
// lists (16x16-pixel tiles); 2 one workgroup per tile over its list.

#include "frame.glsl"
#include "splat_records.glsl"
#include "splat_pixel.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    uint n;          // record slots (quads from 0 up, points from n-1 down)
    uint mode;       // 0 per-splat invocations, 1 binning of the big list, 2 tiles
    uint groups;     // mode 1: workgroups dispatched
    uint big_pixels; // mode 0: a splat whose bound holds more pixels goes to the list
} P;

layout(std430, set = 0, binding = 5) readonly buffer RecA { vec4 recA[]; };
layout(std430, set = 0, binding = 6) readonly buffer RecB { uvec4 recB[]; };
layout(std430, set = 0, binding = 7) readonly buffer Draws { uint draws[8]; };
#if CRAST_PASS == 0
layout(std430, set = 0, binding = 10) buffer VisMin { uint64_t vis[]; };  // per pixel, row-major
#else
layout(std430, set = 0, binding = 10) readonly buffer VisRead { uvec2 vis[]; }; // .y: window depth bits
layout(std430, set = 0, binding = 11) buffer AccC { vec4 acc_c[]; };        // w*rgb, w
layout(std430, set = 0, binding = 12) buffer AccN { vec4 acc_n[]; };        // w*normal, w*depth
#endif
// the big-splat list: big[0] the count, then record slots
layout(std430, set = 0, binding = 13) buffer BigList { uint big[]; };
// per tile: the count of big splats overlapping it, then TILE_CAP entries per tile
layout(std430, set = 0, binding = 16) buffer TileBins { uint bins[]; };

struct Rec {
    vec4 ms_cn, mt_tc, mw_r, center;
    vec3 color, normal;
    uint index;
    ivec2 lo, hi;     // inclusive pixel range
};

vec3 oct_decode(vec2 e) {
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return normalize(n);
}

Rec load(uint slot, bool quad) {
    Rec R;
    R.ms_cn = recA[RECA_STRIDE * slot + RECA_MS_CN];
    R.mt_tc = recA[RECA_STRIDE * slot + RECA_MT_TC];
    R.mw_r = recA[RECA_STRIDE * slot + RECA_MW_R];
    uvec4 b0 = recB[RECB_STRIDE * slot + RECB_CENTER], b1 = recB[RECB_STRIDE * slot + RECB_PACKED];
    float lp = F.depth_params.w;
    R.center = vec4(uintBitsToFloat(b0.x), uintBitsToFloat(b0.y), 1.0 / (lp * lp), uintBitsToFloat(b0.z));
    R.index = b0.w;
    R.color = unpackUnorm4x8(b1.z).rgb;
    R.normal = oct_decode(unpackSnorm2x16(b1.w));
    vec2 lo, hi;
    if (quad) {
        lo = vec2(float(b1.x & 0xFFFFu), float(b1.x >> 16)) * (1.0 / 16.0);   // pixels, 12.4 fixed point
        hi = vec2(float(b1.y & 0xFFFFu), float(b1.y >> 16)) * (1.0 / 16.0);
    } else {
        float h = 0.5 * uintBitsToFloat(b1.x);
        lo = R.center.xy - h;
        hi = R.center.xy + h;
    }
    // pixel x is covered when lo.x <= x + 0.5 < hi.x (top-left rule)
    R.lo = max(ivec2(ceil(lo - 0.5)), ivec2(0));
    R.hi = min(ivec2(ceil(hi - 0.5)) - 1, ivec2(F.viewport.xy) - 1);
    return R;
}

void pixel(Rec R, ivec2 p) {
    float r, depth, zwin;
    vec2 fc = vec2(p) + 0.5;
    uint k = uint(p.y) * uint(F.viewport.x) + uint(p.x);
#if CRAST_PASS == 0
    if (!splat_pixel(fc, R.ms_cn, R.mt_tc, R.mw_r, R.center, true, r, depth, zwin)) return;
    atomicMin(vis[k], (uint64_t(floatBitsToUint(zwin)) << 32) | uint64_t(R.index));
#else
    if (!splat_pixel(fc, R.ms_cn, R.mt_tc, R.mw_r, R.center, false, r, depth, zwin)) return;
    uint vz = vis[k].y;
    float zv = vz == 0xFFFFFFFFu ? 1.0 : uintBitsToFloat(vz);     // cleared: the depth buffer's 1.0
    if (!(zwin <= zv)) return;
    float w = exp(-F.misc.x * r);
    vec3 c = R.color * w, nn = R.normal * w;
    atomicAdd(acc_c[k].x, c.x);
    atomicAdd(acc_c[k].y, c.y);
    atomicAdd(acc_c[k].z, c.z);
    atomicAdd(acc_c[k].w, w);
    atomicAdd(acc_n[k].x, nn.x);
    atomicAdd(acc_n[k].y, nn.y);
    atomicAdd(acc_n[k].z, nn.z);
    atomicAdd(acc_n[k].w, depth * w);
#endif
}

// The tiles (TILE x TILE pixels) of the image, row-major.
const int TILE = 16;
const uint TILE_CAP = 128u;     // list entries per tile; a fuller tile scans the whole big-splat list
ivec2 tile_grid() { return (ivec2(F.viewport.xy) + TILE - 1) / TILE; }

// Mode 2: one workgroup per tile, its 64 invocations own 4 pixels each and
// keep their nearest sample (visibility) or their sums (attributes) in
// registers over the tile's big splats; one atomic per pixel at the end
// (the per-splat invocations of mode 0 write the same pixels).
void tile_pass() {
    ivec2 grid = tile_grid();
    ivec2 t = ivec2(gl_WorkGroupID.xy);
    uint ti = uint(t.y * grid.x + t.x);
    ivec2 t0 = t * TILE, t1 = min(t0 + TILE, ivec2(F.viewport.xy)) - 1;
    ivec2 l = ivec2(gl_LocalInvocationIndex % 8u, gl_LocalInvocationIndex / 8u);
    ivec2 px[4] = ivec2[4](t0 + l, t0 + l + ivec2(8, 0), t0 + l + ivec2(0, 8), t0 + l + ivec2(8, 8));
    uint W = uint(F.viewport.x);
#if CRAST_PASS == 0
    uint64_t best[4] = uint64_t[4](~0ul, ~0ul, ~0ul, ~0ul);
#else
    vec4 ac[4] = vec4[4](vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));
    vec4 an[4] = vec4[4](vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));
    float zv[4];
    for (int q = 0; q < 4; ++q) {
        uint vz = all(lessThanEqual(px[q], t1)) ? vis[uint(px[q].y) * W + uint(px[q].x)].y : 0u;
        zv[q] = vz == 0xFFFFFFFFu ? 1.0 : uintBitsToFloat(vz);
    }
#endif
    uint listed = bins[ti];
    bool scan = listed > TILE_CAP;                 // overfull: every big splat, bounds tested
    uint count = scan ? big[0] : listed;
    uint base = uint(grid.x * grid.y) + ti * TILE_CAP;
    for (uint j = 0u; j < count; ++j) {
        uint slot = scan ? big[1u + j] : bins[base + j];
        Rec R = load(slot, slot < draws[1]);
        if (any(greaterThan(R.lo, t1)) || any(lessThan(R.hi, t0))) continue;
        for (int q = 0; q < 4; ++q) {
            ivec2 p = px[q];
            if (any(lessThan(p, R.lo)) || any(greaterThan(p, R.hi))) continue;
            float r, depth, zwin;
#if CRAST_PASS == 0
            if (!splat_pixel(vec2(p) + 0.5, R.ms_cn, R.mt_tc, R.mw_r, R.center, true, r, depth, zwin)) continue;
            best[q] = min(best[q], (uint64_t(floatBitsToUint(zwin)) << 32) | uint64_t(R.index));
#else
            if (!splat_pixel(vec2(p) + 0.5, R.ms_cn, R.mt_tc, R.mw_r, R.center, false, r, depth, zwin)) continue;
            if (!(zwin <= zv[q])) continue;
            float w = exp(-F.misc.x * r);
            ac[q] += vec4(R.color * w, w);
            an[q] += vec4(R.normal * w, depth * w);
#endif
        }
    }
    for (int q = 0; q < 4; ++q) {
        ivec2 p = px[q];
        if (any(greaterThan(p, t1))) continue;
        uint k = uint(p.y) * W + uint(p.x);
#if CRAST_PASS == 0
        if (best[q] != ~0ul) atomicMin(vis[k], best[q]);
#else
        if (ac[q].w > 0.0) {
            atomicAdd(acc_c[k].x, ac[q].x);
            atomicAdd(acc_c[k].y, ac[q].y);
            atomicAdd(acc_c[k].z, ac[q].z);
            atomicAdd(acc_c[k].w, ac[q].w);
            atomicAdd(acc_n[k].x, an[q].x);
            atomicAdd(acc_n[k].y, an[q].y);
            atomicAdd(acc_n[k].z, an[q].z);
            atomicAdd(acc_n[k].w, an[q].w);
        }
#endif
    }
}

void main() {
    if (P.mode == 0u) {
        // 2D dispatch when the slots need more than maxComputeWorkGroupCount[0] groups
        uint slot = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationIndex;
        if (slot >= P.n) return;
        bool quad = slot < draws[1];
        if (!quad && slot < P.n - draws[5]) return;
        Rec R = load(slot, quad);
        ivec2 ext = R.hi - R.lo + 1;
        if (ext.x <= 0 || ext.y <= 0) return;
        if (uint(ext.x) * uint(ext.y) > P.big_pixels) {
            big[1u + atomicAdd(big[0], 1u)] = slot;
            return;
        }
        for (int y = R.lo.y; y <= R.hi.y; ++y)
            for (int x = R.lo.x; x <= R.hi.x; ++x)
                pixel(R, ivec2(x, y));
        return;
    }
    if (P.mode == 1u) {          // binning: the big splats into the lists of the tiles they overlap
        ivec2 grid = tile_grid();
        uint count = big[0];
        for (uint j = gl_GlobalInvocationID.x; j < count; j += P.groups * 64u) {
            uint slot = big[1u + j];
            Rec R = load(slot, slot < draws[1]);
            ivec2 a = R.lo / TILE, b = R.hi / TILE;
            for (int ty = a.y; ty <= b.y; ++ty)
                for (int tx = a.x; tx <= b.x; ++tx) {
                    uint ti = uint(ty * grid.x + tx);
                    uint e = atomicAdd(bins[ti], 1u);
                    if (e < TILE_CAP) bins[uint(grid.x * grid.y) + ti * TILE_CAP + e] = slot;
                }
        }
        return;
    }
    tile_pass();
}

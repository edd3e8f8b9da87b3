#version 450
#extension GL_GOOGLE_include_directive : require
// Tile rasterizer, scan step 3: each visible Gaussian's first slot (the
// block's slot + an exclusive scan inside the block; invocation t takes the
// TITEMS consecutive Gaussians t * TITEMS..) and its (tile, Gaussian) pairs,
// tiles in row order, Gaussians in depth order.  Pairs past the capacity are
// dropped (the renderer grows the buffers and draws again).
#include "gs_common.glsl"
#include "gs_tile.glsl"

layout(local_size_x = 256) in;
shared uint s_scan[256];

void main() {
    uint t = gl_LocalInvocationIndex, b = gl_WorkGroupID.x, n = tscan[7];
    uint j0 = b * TBLOCK + t * TITEMS;
    uint sum = 0u;
    for (uint r = 0u; r < TITEMS; ++r)
        if (j0 + r < n) sum += tile_count(order[j0 + r]);
    s_scan[t] = sum;
    barrier();
    for (uint o = 1u; o < 256u; o <<= 1u) {
        uint add = t >= o ? s_scan[t - o] : 0u;
        barrier();
        s_scan[t] += add;
        barrier();
    }
    uint slot = tscan[8u + b] + s_scan[t] - sum;
    for (uint r = 0u; r < TITEMS; ++r) {
        if (j0 + r >= n) break;
        uint g = order[j0 + r];
        uvec2 lo, hi;
        if (!tile_rect(g, lo, hi)) continue;
        for (uint y = lo.y; y <= hi.y; ++y)
            for (uint x = lo.x; x <= hi.x; ++x) {
                if (slot < TP.capacity) {
                    pair_keys[slot] = y * TP.tiles_x + x;
                    pair_vals[slot] = g;
                }
                ++slot;
            }
    }
}

#version 450
#extension GL_GOOGLE_include_directive : require
// Tile rasterizer: each tile's run [first, end) of the pairs sorted by tile
// (the ranges start zeroed: a tile without pairs keeps [0, 0)).  Dispatched
// by the tile sort's arguments: one workgroup per 2048 pairs.
#include "gs_common.glsl"
#include "gs_tile.glsl"

layout(local_size_x = 256) in;

void main() {
    uint t = gl_LocalInvocationIndex, b = gl_WorkGroupID.x, n = targs[3];
    for (uint r = 0u; r < TITEMS; ++r) {
        uint k = b * TBLOCK + r * 256u + t;
        if (k >= n) break;
        uint key = pair_keys[k];
        if (k == 0u || pair_keys[k - 1u] != key) ranges[key].x = k;
        if (k + 1u == n || pair_keys[k + 1u] != key) ranges[key].y = k + 1u;
    }
}

#version 450
#extension GL_GOOGLE_include_directive : require
// Tile rasterizer, scan step 1: the tile count of a block of TBLOCK visible
// Gaussians in depth order.
#include "gs_common.glsl"
#include "gs_tile.glsl"

layout(local_size_x = 256) in;
shared uint s_sum[256];

void main() {
    uint t = gl_LocalInvocationIndex, b = gl_WorkGroupID.x, n = tscan[7];
    uint sum = 0u;
    for (uint r = 0u; r < TITEMS; ++r) {
        uint j = b * TBLOCK + r * 256u + t;
        if (j < n) sum += tile_count(order[j]);
    }
    s_sum[t] = sum;
    barrier();
    for (uint o = 128u; o > 0u; o >>= 1u) {
        if (t < o) s_sum[t] += s_sum[t + o];
        barrier();
    }
    if (t == 0u) tscan[8u + b] = s_sum[0];
}

#version 450
#extension GL_GOOGLE_include_directive : require
// Tile rasterizer, scan step 2 (one workgroup): the blocks' tile counts ->
// their first slots (exclusive scan), the pairs wanted and kept.
#include "gs_common.glsl"
#include "gs_tile.glsl"

layout(local_size_x = 256) in;
shared uint s_scan[256];

void main() {
    uint t = gl_LocalInvocationIndex, nb = tscan[4];
    uint carry = 0u;
    for (uint c = 0u; c < nb; c += 256u) {
        uint j = c + t;
        uint v = j < nb ? tscan[8u + j] : 0u;
        s_scan[t] = v;
        barrier();
        for (uint o = 1u; o < 256u; o <<= 1u) {
            uint add = t >= o ? s_scan[t - o] : 0u;
            barrier();
            s_scan[t] += add;
            barrier();
        }
        if (j < nb) tscan[8u + j] = carry + s_scan[t] - v;
        carry += s_scan[255];
        barrier();
    }
    if (t == 0u) {
        tscan[0] = carry;
        tscan[2] = min(carry, TP.capacity);
    }
}

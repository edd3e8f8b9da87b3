#version 450
#extension GL_GOOGLE_include_directive : require
// Radix sort, one pass: the digit histogram of one block of keys.
#include "gs_radix.glsl"

layout(local_size_x = 256) in;
shared uint s_hist[RADIX];

void main() {
    uint t = gl_LocalInvocationIndex;
    uint b = gl_WorkGroupID.x;
    uint n = args[3];
    uint nb = radix_blocks(n);
    s_hist[t] = 0u;
    barrier();
    for (uint r = 0u; r < ITEMS; ++r) {
        uint i = b * BLOCK + r * RADIX + t;
        if (i < n) atomicAdd(s_hist[(keys_in[i] >> RP.shift) & 0xFFu], 1u);
    }
    barrier();
    hist[RADIX + t * nb + b] = s_hist[t];
}

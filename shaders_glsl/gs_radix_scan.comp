#version 450
#extension GL_GOOGLE_include_directive : require
// Radix sort, one pass: workgroup d scans digit d's block counts (exclusive,
// in place, in chunks of 256 with a running carry) and stores the digit's total.
#include "gs_radix.glsl"

layout(local_size_x = 256) in;
shared uint s_scan[RADIX];

void main() {
    uint t = gl_LocalInvocationIndex;
    uint d = gl_WorkGroupID.x;
    uint nb = radix_blocks(args[3]);
    uint carry = 0u;
    for (uint c = 0u; c < nb; c += RADIX) {
        uint j = c + t;
        uint v = j < nb ? hist[RADIX + d * nb + j] : 0u;
        s_scan[t] = v;
        barrier();
        for (uint o = 1u; o < RADIX; o <<= 1u) {          // Hillis-Steele inclusive scan
            uint add = t >= o ? s_scan[t - o] : 0u;
            barrier();
            s_scan[t] += add;
            barrier();
        }
        if (j < nb) hist[RADIX + d * nb + j] = carry + s_scan[t] - v;
        carry += s_scan[RADIX - 1u];
        barrier();
    }
    if (t == 0u) hist[d] = carry;
}

#version 450
#extension GL_GOOGLE_include_directive : require
// Radix sort: the element count (clamped to the capacity) and the indirect
// dispatch of one workgroup per block of keys.
#include "gs_radix.glsl"

layout(local_size_x = 1) in;

void main() {
    uint n = min(count_words[RP.count_index], RP.capacity);
    args[0] = radix_blocks(n);
    args[1] = 1u;
    args[2] = 1u;
    args[3] = n;
}

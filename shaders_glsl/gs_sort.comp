#version 450
#extension GL_GOOGLE_include_directive : require
// One compare-exchange step (k, j) of a bitonic sort of (keys, order) in
// ascending key order; sort length F.counts.z is a power of two.
#include "gs_common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { uint k; uint j; } P;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint l = i ^ P.j;
    if (i >= F.counts.z || l <= i) return;
    uint a = keys[i], b = keys[l];
    bool up = (i & P.k) == 0u;
    if (up ? a > b : a < b) {
        keys[i] = b; keys[l] = a;
        uint t = order[i]; order[i] = order[l]; order[l] = t;
    }
}

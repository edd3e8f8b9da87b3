#version 450
// One compare-exchange step (k, j) of a bitonic sort of (keys, values) in
// ascending key order, sort length n a power of two (the sort the radix sort
// replaced; splatedit/render/gaussian/gpu_sort.py keeps it for comparison).

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { uint k; uint j; uint n; } P;
layout(std430, set = 0, binding = 0) buffer BKeys { uint keys[]; };
layout(std430, set = 0, binding = 1) buffer BVals { uint vals[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint l = i ^ P.j;
    if (i >= P.n || l <= i) return;
    uint a = keys[i], b = keys[l];
    bool up = (i & P.k) == 0u;
    if (up ? a > b : a < b) {
        keys[i] = b; keys[l] = a;
        uint t = vals[i]; vals[i] = vals[l]; vals[l] = t;
    }
}

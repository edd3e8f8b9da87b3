#version 450
#extension GL_GOOGLE_include_directive : require
// Tile rasterizer: the visible count (the pre-pass's draws[1]) -> the
// dispatch of the scan passes; clears the pair counts.
#include "gs_common.glsl"
#include "gs_tile.glsl"

layout(local_size_x = 1) in;

void main() {
    uint n = draws[1];
    tscan[0] = 0u;
    tscan[2] = 0u;
    tscan[4] = (n + TBLOCK - 1u) / TBLOCK;
    tscan[5] = 1u;
    tscan[6] = 1u;
    tscan[7] = n;
}

#version 450
#extension GL_GOOGLE_include_directive : require
// Tile rasterizer blend into an RGBA32F accumulator.
#define ACCUM_FORMAT rgba32f
#include "gs_tile_blend.glsl"

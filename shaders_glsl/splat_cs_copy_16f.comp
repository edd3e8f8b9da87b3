#version 450
#extension GL_GOOGLE_include_directive : require
// Compute rasterizer: the accumulation buffers into rgba16f-format accumulator images.
#define ACCUM_FORMAT rgba16f
#include "splat_cs_copy.glsl"

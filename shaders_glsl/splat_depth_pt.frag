#version 450
#extension GL_GOOGLE_include_directive : require
// Pass 0 for square points: depth from the vertex shader (see splat_fs.glsl).
#define SPLAT_PASS 0
#define SPLAT_EXACT_DEPTH 0
#include "splat_fs.glsl"

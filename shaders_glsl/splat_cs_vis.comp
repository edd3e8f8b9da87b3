#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
// Compute rasterizer, visibility (64-bit atomicMin of depth and index).
#define CRAST_PASS 0
#include "splat_cs_raster.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_atomic_float : require
// Compute rasterizer, attribute accumulation (float32 atomicAdd).
#define CRAST_PASS 1
#include "splat_cs_raster.glsl"

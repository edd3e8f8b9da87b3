#version 450
#extension GL_GOOGLE_include_directive : require
// Radix sort scatter, shared-memory variant (no subgroup operations): groups
// of GROUP_SIZE slots rank by comparing digits in shared memory.
#define GROUP_SIZE 16u
#include "gs_radix.glsl"
#include "gs_radix_scatter.glsl"

#version 450
// spirv: vulkan1.1
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
// Radix sort scatter, subgroup variant: the equal digits of a subgroup by
// eight ballots (one per digit bit; the "warp-level multisplit" of Ashkiani
// et al. 2017), ranks by exclusive bit counts.  For subgroups of 8..128
// invocations that divide 256 (gpu_sort.py checks).
#define SUBGROUP 1
#include "gs_radix.glsl"
#include "gs_radix_scatter.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
// Splat vertex shader, deformation basis with 4 columns (one control frame).
#define BASIS_GROUPS 1
#include "splat_vs.glsl"

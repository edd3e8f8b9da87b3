#version 450
#extension GL_GOOGLE_include_directive : require
// Splat vertex shader, deformation basis with 12 columns.
#define BASIS_GROUPS 3
#include "splat_vs.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
// Splat vertex shader, deformation basis with 16 columns.
#define BASIS_GROUPS 4
#include "splat_vs.glsl"

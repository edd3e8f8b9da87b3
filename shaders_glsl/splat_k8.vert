#version 450
#extension GL_GOOGLE_include_directive : require
// Splat vertex shader, deformation basis with 8 columns (e.g. two handles).
#define BASIS_GROUPS 2
#include "splat_vs.glsl"

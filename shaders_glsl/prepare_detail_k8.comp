#version 450
#extension GL_GOOGLE_include_directive : require
// Compute pre-pass of the detail-preserving mode, deformation basis with 8 columns.
#define BASIS_GROUPS 2
#define DETAIL 1
#include "prepare_cs.glsl"

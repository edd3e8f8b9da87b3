#version 450
#extension GL_GOOGLE_include_directive : require
// Compute pre-pass of the detail-preserving mode, deformation basis with 16 columns.
#define BASIS_GROUPS 4
#define DETAIL 1
#include "prepare_cs.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
// Compute pre-pass, deformation basis with 12 columns.
#define BASIS_GROUPS 3
#include "prepare_cs.glsl"

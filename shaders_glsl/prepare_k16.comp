#version 450
#extension GL_GOOGLE_include_directive : require
// Compute pre-pass, deformation basis with 16 columns.
#define BASIS_GROUPS 4
#include "prepare_cs.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
#define SPLAT_PASS 0
#include "splat_fs.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
// Gaussian splatting: the background under what the transmittance left,
// C + T * background (display values; decoded for an sRGB-encoding target).
#include "gs_common.glsl"

layout(set = 0, binding = 10) uniform sampler2D accum;   // premultiplied rgb, 1 - T
layout(location = 0) out vec4 o_color;

void main() {
    vec4 a = texelFetch(accum, ivec2(gl_FragCoord.xy), 0);
    vec3 rgb = clamp(a.rgb + (1.0 - a.a) * F.background.rgb, 0.0, 1.0);
    if (F.counts.w != 0u)
        rgb = mix(rgb / 12.92, pow((rgb + 0.055) / 1.055, vec3(2.4)), greaterThan(rgb, vec3(0.04045)));
    o_color = vec4(rgb, 1.0);
}

#version 450
#extension GL_GOOGLE_include_directive : require
// Pass 3: normalise the accumulated attributes and shade (deferred Phong with
// a headlight), background colour, gamma.  Heat-map mode (F.options.z == 1):
// the accumulated colour is the encoded stretch of distortion.glsl.
#include "frame.glsl"
#include "distortion.glsl"

layout(set = 0, binding = 1) uniform sampler2D accum_color;   // w*rgb, w
layout(set = 0, binding = 2) uniform sampler2D accum_normal;  // w*n, w*depth
layout(location = 0) out vec4 o_color;

void main() {
    ivec2 ip = ivec2(gl_FragCoord.xy);
    vec4 a = texelFetch(accum_color, ip, 0);
    vec4 b = texelFetch(accum_normal, ip, 0);
    if (!(a.a >= F.misc.z)) { o_color = F.background; return; }
    vec3 col = a.rgb / a.a;
    if (F.options.z == 1u) col = heat_resolve(col);
    vec3 n = normalize(b.xyz);
    float depth = b.w / a.a;
    vec3 ray = vec3(F.pix_to_ray.x * gl_FragCoord.x + F.pix_to_ray.y,
                    F.pix_to_ray.z * gl_FragCoord.y + F.pix_to_ray.w, -1.0);
    vec3 V = normalize(-ray);                              // towards the eye = headlight direction
    float diff = max(dot(n, V), 0.0);
    vec3 R = reflect(-V, n);
    float spec = pow(max(dot(R, V), 0.0), F.light.w);
    vec3 rgb = col * (F.light.x + F.light.y * diff) + F.light.z * spec;
    rgb = clamp(rgb, 0.0, 1.0);
    if (F.options.y != 0u) rgb = pow(rgb, vec3(F.misc.y));
    o_color = vec4(rgb, 1.0);
}

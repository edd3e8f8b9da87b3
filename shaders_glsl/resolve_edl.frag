#version 450
#extension GL_GOOGLE_include_directive : require
// The resolve pass with eye-dome lighting (frame_passes.EyeDomeResolve): the
// shading of resolve.frag, then each covered pixel's colour multiplied by
// exp(-300 * strength * S / 8), S = sum over the 8 neighbours at radius r
// (pixels) of max(0, log2(depth) - log2(depth_neighbour)), depth the linear
// view depth (the accumulated w*depth / w); an uncovered neighbour (or one
// outside the image) counts as the far plane, so it never darkens a covered
// pixel, and uncovered pixels stay background: no outline is drawn around
// silhouettes (Boucheny 2009, "Interactive scientific visualization of large
// datasets", ch. 4; the 300 is his scale).
// F.display.z = strength, F.display.w = radius r (pixels).  Steps below
// NOISE_LOG2 count as none: the rgba16f accumulators hold w*depth and w to
// 2^-11 relative each, so a flat surface's log2(depth) jitters by up to
// ~0.003 between pixels (measured: without this, flat areas of
// tests/render/test_edl.py darken by up to 45/255).
#include "frame.glsl"
#include "distortion.glsl"

layout(set = 0, binding = 1) uniform sampler2D accum_color;   // w*rgb, w
layout(set = 0, binding = 2) uniform sampler2D accum_normal;  // w*n, w*depth
layout(location = 0) out vec4 o_color;

const float NOISE_LOG2 = 0.004;

// log2 of the view depth at pixel ip (uncovered or outside the image: the far plane)
float log_depth(ivec2 ip) {
    ivec2 size = ivec2(F.viewport.xy);
    float far = F.depth_params.y;
    if (any(lessThan(ip, ivec2(0))) || any(greaterThanEqual(ip, size))) return log2(far);
    float w = texelFetch(accum_color, ip, 0).a;
    if (!(w >= F.misc.z)) return log2(far);
    return log2(max(texelFetch(accum_normal, ip, 0).w / w, 1e-20));
}

void main() {
    ivec2 ip = ivec2(gl_FragCoord.xy);
    vec4 a = texelFetch(accum_color, ip, 0);
    vec4 b = texelFetch(accum_normal, ip, 0);
    if (!(a.a >= F.misc.z)) { o_color = F.background; return; }
    vec3 col = a.rgb / a.a;
    if (F.options.z == 1u) col = heat_resolve(col);
    vec3 n = normalize(b.xyz);
    vec3 ray = vec3(F.pix_to_ray.x * gl_FragCoord.x + F.pix_to_ray.y,
                    F.pix_to_ray.z * gl_FragCoord.y + F.pix_to_ray.w, -1.0);
    vec3 V = normalize(-ray);                              // towards the eye = headlight direction
    float diff = max(dot(n, V), 0.0);
    vec3 R = reflect(-V, n);
    float spec = pow(max(dot(R, V), 0.0), F.light.w);
    vec3 rgb = col * (F.light.x + F.light.y * diff) + F.light.z * spec;
    rgb = clamp(rgb, 0.0, 1.0);

    // eye-dome lighting
    float ld = log2(max(b.w / a.a, 1e-20));
    float r = F.display.w;
    float s = 0.0;
    for (int k = 0; k < 8; ++k) {
        float ang = 0.78539816 * float(k);
        ivec2 off = ivec2(round(r * vec2(cos(ang), sin(ang))));
        s += max(0.0, ld - log_depth(ip + off) - NOISE_LOG2);
    }
    rgb *= exp(-300.0 * F.display.z * s / 8.0);

    if (F.options.y != 0u) rgb = pow(rgb, vec3(F.misc.y));
    o_color = vec4(rgb, 1.0);
}

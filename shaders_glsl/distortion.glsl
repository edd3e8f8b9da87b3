// Distortion heat map (F.options.z == 1; splatedit/deform/distortion.py has
// the same definitions on the CPU).
//
// Principal stretches s1 >= s2 of the map of a splat's tangent plane taking
// its axes (u0, v0) to (u1, v1) = (J u0, J v0): square roots of the
// eigenvalues of G0^-1 G1 (Gram matrices of the two axis pairs; for
// orthogonal axes the singular values of [J u0/|u0|, J v0/|v0|]).
// stretch = max(s1, 1/s2) >= 1.
//
// The splat passes carry the stretch in the colour channels (accumulated with
// the splat weights like any colour, so it is filtered like the image):
//   r = log(stretch) / log(HEAT_MAX_STRETCH), clamped to 0..1
//   g = 1 for support splats (FLAG_SUPPORT or FLAG_DEFORMED), else 0
//   b = the splat's own linear luminance (non-support splats are drawn grey)
// and the resolve pass maps r / g through heat_ramp().

// Mirrors splatedit/tolerances.py DISTORTION_HEAT_MAX_STRETCH (a test checks).
const float HEAT_MAX_STRETCH = 4.0;

float splat_stretch(vec3 u0, vec3 v0, vec3 u1, vec3 v1) {
    float e0 = dot(u0, u0), f0 = dot(u0, v0), g0 = dot(v0, v0);
    float e1 = dot(u1, u1), f1 = dot(u1, v1), g1 = dot(v1, v1);
    float det0 = e0 * g0 - f0 * f0;
    if (!(det0 > 0.0)) return HEAT_MAX_STRETCH;
    float m00 = (g0 * e1 - f0 * f1) / det0, m01 = (g0 * f1 - f0 * g1) / det0;
    float m10 = (e0 * f1 - f0 * e1) / det0, m11 = (e0 * g1 - f0 * f1) / det0;
    float half_tr = 0.5 * (m00 + m11), dd = 0.5 * (m00 - m11);
    float s1 = sqrt(max(half_tr + sqrt(max(dd * dd + m01 * m10, 0.0)), 0.0));
    float area = length(cross(u1, v1)) / length(cross(u0, v0));
    float s2 = s1 > 0.0 ? area / s1 : 0.0;
    return s2 > 0.0 ? max(s1, 1.0 / s2) : HEAT_MAX_STRETCH;
}

// The encoded colour of a splat in heat-map mode (see above).
vec3 heat_encode(float stretch, vec3 srgb, uint flags) {
    float t = clamp(log(max(stretch, 1.0)) / log(HEAT_MAX_STRETCH), 0.0, 1.0);
    float sup = (flags & (FLAG_SUPPORT | FLAG_DEFORMED)) != 0u ? 1.0 : 0.0;
    float lum = dot(pow(srgb, vec3(2.2)), vec3(0.2126, 0.7152, 0.0722));
    return vec3(t * sup, sup, lum);
}

// Sequential ramp over t = log(stretch) / log(4), in sRGB (after ColorBrewer
// YlOrRd: hue from yellow to red with monotonically falling lightness, so it
// reads in order and in grey): 1x light neutral grey, 1.5x pale yellow,
// 2x orange, 3x red, 4x and beyond dark red.  Returns linear rgb.
vec3 heat_ramp(float t) {
    const float T15 = 0.29248125;   // log(1.5) / log(4)
    const float T3 = 0.79248125;    // log(3) / log(4)
    vec3 c;
    if (t < T15) c = mix(vec3(0.90, 0.90, 0.88), vec3(1.00, 0.93, 0.55), t / T15);
    else if (t < 0.5) c = mix(vec3(1.00, 0.93, 0.55), vec3(0.99, 0.62, 0.25), (t - T15) / (0.5 - T15));
    else if (t < T3) c = mix(vec3(0.99, 0.62, 0.25), vec3(0.89, 0.10, 0.11), (t - 0.5) / (T3 - 0.5));
    else c = mix(vec3(0.89, 0.10, 0.11), vec3(0.50, 0.00, 0.15), (t - T3) / (1.0 - T3));
    return pow(c, vec3(2.2));
}

// Resolve-pass colour of an accumulated heat-map texel (normalised e = (r, g, b)).
vec3 heat_resolve(vec3 e) {
    vec3 grey = vec3(0.10 + 0.20 * sqrt(clamp(e.b, 0.0, 1.0)));    // non-support: darker neutral grey
    if (!(e.g > 1e-3)) return grey;
    return mix(grey, heat_ramp(clamp(e.r / e.g, 0.0, 1.0)), clamp(e.g, 0.0, 1.0));
}

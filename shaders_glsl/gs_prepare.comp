#version 450
#extension GL_GOOGLE_include_directive : require
// Gaussian splatting pre-pass, once per Gaussian per frame: deformation
// (p + B dC, J Sigma J^T, polar rotation of J for the SH), EWA projection to a
// screen conic, SH colour, culling, depth key.  Threads n .. sort length - 1
// pad the sort with culled keys.  With P.compact the visible Gaussians append
// (key, index) to keys / order instead (slots taken in groups of the
// workgroup, draws[1] counts them), for the GPU radix sort of only those.
#include "gs_common.glsl"
#define DEFORM_BINDING 9
#include "deform.glsl"
#include "rotation.glsl"
const uint FLAG_SUPPORT = 1u;     // gflags bits (renderer.py FLAG_*), for distortion.glsl
const uint FLAG_DEFORMED = 4u;
#include "distortion.glsl"

// Heat-map colour (display values) of a Gaussian: the principal stretch of J on
// its own plane (normal n = its shortest axis; the splat renderer's measure of
// the proxy disc) through the ramp for support Gaussians, a dark grey of its
// luminance for the others (as heat_resolve draws them).
vec3 gs_heat(vec3 col, vec3 n, mat3 J, bool deformed, uint fl) {
    vec3 lin = pow(col, vec3(2.2));
    if (!deformed && (fl & FLAG_SUPPORT) == 0u)
        return pow(vec3(0.10 + 0.20 * sqrt(clamp(dot(lin, vec3(0.2126, 0.7152, 0.0722)), 0.0, 1.0))),
                   vec3(1.0 / 2.2));
    vec3 t0 = normalize(cross(n, abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0)));
    vec3 t1 = cross(n, t0);
    float st = deformed ? splat_stretch(t0, t1, J * t0, J * t1) : 1.0;
    return pow(heat_ramp(clamp(log(max(st, 1.0)) / log(HEAT_MAX_STRETCH), 0.0, 1.0)), vec3(1.0 / 2.2));
}

// the group g of 4 basis columns: dp += B dC, Jm += dC^T grad B (J = I + Jm), as splat_math.glsl;
// a rotating handle (rotation-aware mode) adds its blended arc and that arc's Jacobian
void deform_group(uint g, vec4 B, vec4 Bx, vec4 By, vec4 Bz, inout vec3 dp, inout mat3 Jm) {
    vec4 dx = D.dC[3u * g], dy = D.dC[3u * g + 1u], dz = D.dC[3u * g + 2u];
    dp += vec3(dot(B, dx), dot(B, dy), dot(B, dz));
    Jm[0] += vec3(dot(dx, Bx), dot(dy, Bx), dot(dz, Bx));
    Jm[1] += vec3(dot(dx, By), dot(dy, By), dot(dz, By));
    Jm[2] += vec3(dot(dx, Bz), dot(dy, Bz), dot(dz, Bz));
    if (D.rot[4u * g].w != 0.0)
        rotation_blend(D.rot[4u * g], D.rot[4u * g + 1u], D.rot[4u * g + 2u], D.rot[4u * g + 3u],
                       B, Bx, By, Bz, dp, Jm);
}

layout(local_size_x = 64) in;
layout(push_constant) uniform Push { uint groups; uint polar_iterations; uint compact; } P;
shared uint s_count;
shared uint s_base;

// the view depth z > 0 as a key whose unsigned order is its float order
// (sign bit set; gpu_sort.py sortable_float_keys for any sign)
uint sortable_depth(float z) {
    uint b = floatBitsToUint(z);
    return (b & 0x80000000u) != 0u ? ~b : b | 0x80000000u;
}

const float C0 = 0.28209479177387814;
const float C1 = 0.4886025119029199;
const float C2[5] = float[](1.0925484305920792, -1.0925484305920792, 0.31539156525252005,
                            -1.0925484305920792, 0.5462742152960396);
const float C3[7] = float[](-0.5900435899266435, 2.890611442640554, -0.4570457994644658,
                            0.3731763325901154, -0.4570457994644658, 1.445305721320277,
                            -0.5900435899266435);

vec3 sh_rest(uint i, uint k) {     // coefficient k >= 1 of Gaussian i
    uint h = 3u * (k - 1u);
    uint base = i * F.counts.y;
    float c[3];
    for (uint j = 0u; j < 3u; ++j) {
        uint e = h + j;
        vec2 two = unpackHalf2x16(rest[base + e / 2u]);
        c[j] = (e & 1u) == 0u ? two.x : two.y;
    }
    return vec3(c[0], c[1], c[2]);
}

vec3 sh_color(uint i, vec3 dc, vec3 d, int deg) {
    vec3 r = C0 * dc;
    if (deg >= 1) {
        float x = d.x, y = d.y, z = d.z;
        r += -C1 * y * sh_rest(i, 1u) + C1 * z * sh_rest(i, 2u) - C1 * x * sh_rest(i, 3u);
        if (deg >= 2) {
            float xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, xz = x * z;
            r += C2[0] * xy * sh_rest(i, 4u) + C2[1] * yz * sh_rest(i, 5u)
                 + C2[2] * (2.0 * zz - xx - yy) * sh_rest(i, 6u) + C2[3] * xz * sh_rest(i, 7u)
                 + C2[4] * (xx - yy) * sh_rest(i, 8u);
            if (deg >= 3) {
                r += C3[0] * y * (3.0 * xx - yy) * sh_rest(i, 9u) + C3[1] * xy * z * sh_rest(i, 10u)
                     + C3[2] * y * (4.0 * zz - xx - yy) * sh_rest(i, 11u)
                     + C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy) * sh_rest(i, 12u)
                     + C3[4] * x * (4.0 * zz - xx - yy) * sh_rest(i, 13u)
                     + C3[5] * z * (xx - yy) * sh_rest(i, 14u) + C3[6] * x * (xx - 3.0 * yy) * sh_rest(i, 15u);
            }
        }
    }
    return max(r + 0.5, vec3(0.0));
}

// rotation of the polar decomposition J = R S (Newton: R <- (R + R^-T) / 2)
mat3 polar_rotation(mat3 J) {
    mat3 R = J;
    for (uint it = 0u; it < P.polar_iterations; ++it)
        R = 0.5 * (R + transpose(inverse(R)));
    return R;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint n = F.counts.x;
    bool visible = false;
    uint key = GS_NONE;
    if (i < n) {
        uint g = GEOM_STRIDE * i;
        uint c0 = g + GEOM_CENTER, s0 = g + GEOM_COV, d0 = g + GEOM_SH_DC;
        vec3 p = vec3(geom[c0], geom[c0 + 1u], geom[c0 + 2u]);
        float op = geom[g + GEOM_OPACITY];
        mat3 S = mat3(geom[s0], geom[s0 + 1u], geom[s0 + 2u],
                      geom[s0 + 1u], geom[s0 + 3u], geom[s0 + 4u],
                      geom[s0 + 2u], geom[s0 + 4u], geom[s0 + 5u]);
        vec3 dc = vec3(geom[d0], geom[d0 + 1u], geom[d0 + 2u]);
        vec3 dir = p;
        uint row = brow[i];
        mat3 R = mat3(1.0);
        mat3 J = mat3(1.0);
        bool deformed = row != GS_NONE;
        if (deformed) {
            vec3 dp = vec3(0.0);
            mat3 Jm = mat3(0.0);
            uint b = BASIS_STRIDE * P.groups * row;
            for (uint k = 0u; k < P.groups; ++k)
                deform_group(k, basis[b + BASIS_STRIDE * k + BASIS_B], basis[b + BASIS_STRIDE * k + BASIS_BX],
                             basis[b + BASIS_STRIDE * k + BASIS_BY], basis[b + BASIS_STRIDE * k + BASIS_BZ], dp, Jm);
            p += dp;
            J = mat3(1.0) + Jm;
            S = J * S * transpose(J);
            R = polar_rotation(J);
        }
        S *= F.display.x * F.display.x;       // the editor's splat size (display only)
        vec3 t = (F.view * vec4(p, 1.0)).xyz;
        float z = -t.z;
        if (z > F.params.w && op >= F.limits.w) {
            float fx = F.focal.x, fy = F.focal.y;
            float tx = clamp(t.x / z, -F.limits.x, F.limits.x) * z;
            float ty = clamp(t.y / z, -F.limits.y, F.limits.y) * z;
            // rows of the projection Jacobian (pixels per unit), times the view rotation
            vec3 j0 = vec3(fx / z, 0.0, fx * tx / (z * z));
            vec3 j1 = vec3(0.0, -fy / z, -fy * ty / (z * z));
            mat3 W = mat3(F.view);
            vec3 m0 = transpose(W) * j0, m1 = transpose(W) * j1;   // rows of Jp W
            vec3 Sm0 = S * m0, Sm1 = S * m1;
            float xx = dot(m0, Sm0) + F.limits.z;
            float xy = dot(m0, Sm1);
            float yy = dot(m1, Sm1) + F.limits.z;
            float det = xx * yy - xy * xy;
            vec2 c = vec2(fx * t.x / z + F.focal.z, -fy * t.y / z + F.focal.w);
            if (det > 0.0) {
                float q = 2.0 * log(op / F.limits.w);          // alpha >= floor inside d^T conic d <= q
                float mid = 0.5 * (xx + yy);
                float disc = sqrt(max(mid * mid - det, 0.0));
                float l1 = mid + disc, l2 = max(mid - disc, 0.0);
                vec2 e1 = abs(xy) > 1e-12 * l1 ? normalize(vec2(xy, l1 - xx))
                                               : (xx >= yy ? vec2(1.0, 0.0) : vec2(0.0, 1.0));
                vec2 a1 = sqrt(q * l1) * e1;
                vec2 a2 = sqrt(q * l2) * vec2(-e1.y, e1.x);
                vec2 ext = abs(a1) + abs(a2);
                if (all(greaterThan(c + ext, vec2(0.0))) && all(lessThan(c - ext, F.viewport.xy))) {
                    visible = true;
                    vec3 d = normalize(p - F.eye.xyz);
                    if (deformed) d = transpose(R) * d;
                    vec3 col = sh_color(i, dc, d, int(F.eye.w));
                    if (F.display.y != 0.0) col = vec3(dot(col, vec3(0.2126, 0.7152, 0.0722)));
                    uint fl = gflags[i];
                    if (F.display.z != 0.0) {          // the distortion heat map (the editor's D)
                        uint a0 = g + GEOM_NORMAL;
                        col = gs_heat(col, vec3(geom[a0], geom[a0 + 1u], geom[a0 + 2u]), J, deformed, fl);
                    } else {
                        if ((fl & 1u) != 0u) col = mix(col, F.tint_support.rgb, F.tint_support.a);
                        if ((fl & 2u) != 0u) col = mix(col, F.tint_handle.rgb, F.tint_handle.a);
                        if ((fl & 8u) != 0u) col *= 0.35;
                    }
                    float far = F.viewport.w, near = F.viewport.z;
                    float zn = far * (z - near) / (z * (far - near));
                    rec[REC_STRIDE * i + REC_CENTER] = vec4(c, zn, op);
                    rec[REC_STRIDE * i + REC_CONIC] = vec4(yy / det, -xy / det, xx / det, sqrt(F.params.z / q));
                    rec[REC_STRIDE * i + REC_AXES] = vec4(a1, a2);
                    rec[REC_STRIDE * i + REC_COLOR] = vec4(col, uintBitsToFloat(i + 1u));
                    if (P.compact == 0u) keys[i] = sortable_depth(z);
                    key = sortable_depth(z);
                }
            }
        }
    }
    if (!visible && i < n) rec[REC_STRIDE * i + REC_CENTER] = vec4(0.0);       // the pick pass draws every record
    if (P.compact == 0u) {
        if (!visible && i < F.counts.z) keys[i] = GS_NONE;
        if (i < F.counts.z) order[i] = i;
    }
    if (gl_LocalInvocationIndex == 0u) s_count = 0u;
    barrier();
    uint local = visible ? atomicAdd(s_count, 1u) : 0u;
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_count > 0u) s_base = atomicAdd(draws[1], s_count);
    barrier();
    if (P.compact != 0u && visible) {
        keys[s_base + local] = key;
        order[s_base + local] = i;
    }
}

// Tile rasterizer, the blend: one workgroup per TILE x TILE tile, one
// invocation per pixel.  The tile's Gaussians (front to back) pass through
// shared memory in batches of 256; each pixel sums C += T alpha c, T *= 1 -
// alpha with the quad path's alpha (gs.frag: min(ceiling, opacity exp(power)),
// skipped below the floor) and stops before the Gaussian that would take T
// below t_min (the 3DGS reference's rule, gaussian/reference.py); the
// workgroup stops when every pixel has.  It stores (C, 1 - T) into the
// accumulator that gs_resolve.frag reads (the quad path's premultiplied
// colour and alpha).  Define ACCUM_FORMAT (rgba16f / rgba32f) before the include.
#include "gs_common.glsl"
#include "gs_tile.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
layout(set = 1, binding = 5, ACCUM_FORMAT) uniform writeonly image2D accum_out;

shared vec4 s_geo[256];    // centre xy, conic a, conic b
shared vec4 s_col[256];    // rgb, opacity
shared float s_c[256];     // conic c
shared uint s_done;

void main() {
    uint t = gl_LocalInvocationIndex;
    uvec2 tile = gl_WorkGroupID.xy;
    uvec2 px = tile * TILE + gl_LocalInvocationID.xy;
    bool inside = px.x < uint(F.viewport.x) && px.y < uint(F.viewport.y);
    uvec2 range = ranges[tile.y * TP.tiles_x + tile.x];
    vec2 p = vec2(px) + 0.5;
    vec3 C = vec3(0.0);
    float T = 1.0;
    bool done = !inside;
    if (t == 0u) s_done = 0u;
    barrier();
    if (done) atomicAdd(s_done, 1u);
    for (uint base = range.x; base < range.y; base += 256u) {
        uint k = base + t;
        if (k < range.y) {
            uint g = pair_vals[k];
            vec4 r0 = rec[REC_STRIDE * g + REC_CENTER], r1 = rec[REC_STRIDE * g + REC_CONIC];
            s_geo[t] = vec4(r0.xy, r1.xy);
            s_c[t] = r1.z;
            s_col[t] = vec4(rec[REC_STRIDE * g + REC_COLOR].rgb, r0.w);
        }
        barrier();
        if (!done) {
            uint m = min(256u, range.y - base);
            for (uint q = 0u; q < m; ++q) {
                vec4 geo = s_geo[q];
                vec2 d = p - geo.xy;
                float power = -0.5 * (geo.z * d.x * d.x + s_c[q] * d.y * d.y) - geo.w * d.x * d.y;
                if (power > 0.0) continue;
                vec4 col = s_col[q];
                float alpha = min(F.params.x, col.a * exp(power));
                if (alpha < F.limits.w) continue;
                float next = T * (1.0 - alpha);
                if (next < TP.t_min) {
                    done = true;
                    atomicAdd(s_done, 1u);
                    break;
                }
                C += T * alpha * col.rgb;
                T = next;
            }
        }
        barrier();
        if (s_done == 256u) break;
        barrier();
    }
    if (inside) imageStore(accum_out, ivec2(px), vec4(C, 1.0 - T));
}

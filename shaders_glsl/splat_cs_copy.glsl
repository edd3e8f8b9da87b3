// Copies the compute rasterizer's accumulation buffers (splat_cs_raster.glsl,
// float32 RGBA per pixel, row-major) into the accumulator images that
// resolve.frag reads (the raster path's attribute targets), one invocation per
// pixel.  The including file defines ACCUM_FORMAT (the images' format).
#include "frame.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 11) readonly buffer AccC { vec4 acc_c[]; };
layout(std430, set = 0, binding = 12) readonly buffer AccN { vec4 acc_n[]; };
layout(set = 0, binding = 14, ACCUM_FORMAT) uniform writeonly image2D img_c;
layout(set = 0, binding = 15, ACCUM_FORMAT) uniform writeonly image2D img_n;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(F.viewport.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    uint k = uint(p.y) * uint(size.x) + uint(p.x);
    imageStore(img_c, p, acc_c[k]);
    imageStore(img_n, p, acc_n[k]);
}

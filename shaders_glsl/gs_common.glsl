// Gaussian splatting (issue 13): the frame block and buffers shared by the
// pre-pass, the sort and the draws (set 0).  GsFrame, GsGeom and GsRec are
// declared once as GS_FRAME_UBO, GS_GEOM and GS_REC in
// splatedit/render/uniforms.py; tests/render/test_uniforms.py checks this
// block's members and the GEOM_* / REC_* record constants against them.

layout(std140, set = 0, binding = 0) uniform GsFrame {
    mat4 view;          // GPU model units -> eye (right-handed, looks down -z)
    vec4 focal;         // fx, fy (pixels per unit of x/z, y/z), cx, cy (principal point, pixels)
    vec4 viewport;      // width, height, near, far (GPU units)
    vec4 eye;           // camera position (GPU units), SH degree
    vec4 limits;        // frustum clamp of x/z, of y/z, low-pass (px^2), alpha floor
    vec4 params;        // alpha ceiling, pick min opacity, pick sigmas^2, near cull distance
    vec4 background;    // rgb (display values), -
    uvec4 counts;       // n, uints of SH bands 1-3 per Gaussian, sort length (power of 2), sRGB target
    vec4 tint_support;  // rgb, strength (the splat renderer's selection tints)
    vec4 tint_handle;   // rgb, strength
    vec4 display;       // splat scale (standard deviations times this; display only), grey (1: luminance),
                        // heat map (1: distortion colours), -
} F;

// GEOM_STRIDE floats per Gaussian: centre (3), opacity (1), covariance xx xy xz yy yz zz (6),
// SH DC rgb (3), unit shortest axis (3, the heat map's normal); GEOM_<FIELD>: first float of a field
const uint GEOM_STRIDE = 16u;
const uint GEOM_CENTER = 0u;
const uint GEOM_OPACITY = 3u;
const uint GEOM_COV = 4u;
const uint GEOM_SH_DC = 10u;
const uint GEOM_NORMAL = 13u;
layout(std430, set = 0, binding = 1) readonly buffer GsGeom { float geom[]; };
// SH bands 1-3 as half floats, coefficient-major (k = 1.., then rgb), counts.y uints per Gaussian
layout(std430, set = 0, binding = 2) readonly buffer GsRest { uint rest[]; };
// row of each Gaussian in the basis buffer, 0xFFFFFFFF: not deformed
layout(std430, set = 0, binding = 3) readonly buffer GsBasisRow { uint brow[]; };
// 4 vec4 (B, Bx, By, Bz) per group of 4 columns per deformed row
layout(std430, set = 0, binding = 4) readonly buffer GsBasis { vec4 basis[]; };
// REC_STRIDE vec4 per Gaussian: (px x, px y, ndc depth, opacity), (conic a b c, pick scale),
// (half-axis 1 xy, half-axis 2 xy) in pixels, (rgb, index + 1 as bits)
const uint REC_STRIDE = 4u;
const uint REC_CENTER = 0u;
const uint REC_CONIC = 1u;
const uint REC_AXES = 2u;
const uint REC_COLOR = 3u;
layout(std430, set = 0, binding = 5) buffer GsRec { vec4 rec[]; };
layout(std430, set = 0, binding = 6) buffer GsKeys { uint keys[]; };    // view depth bits, 0xFFFFFFFF culled
layout(std430, set = 0, binding = 7) buffer GsOrder { uint order[]; };  // draw order (front to back)
layout(std430, set = 0, binding = 8) buffer GsDraws { uint draws[4]; }; // VkDrawIndirectCommand

// selection flags per Gaussian (renderer.py FLAG_SUPPORT, FLAG_HANDLE, FLAG_INACTIVE)
layout(std430, set = 0, binding = 11) readonly buffer GsFlags { uint gflags[]; };

const uint GS_NONE = 0xFFFFFFFFu;

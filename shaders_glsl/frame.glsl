// Per-frame uniform block shared by every splatedit shader (std140, set 0 binding 0).
// Declared once as FRAME_UBO in splatedit/render/uniforms.py (the renderer fills it by
// field name in Renderer._write_ubo); tests/render/test_uniforms.py checks that this block
// has the same members, types and std140 offsets.

layout(std140, set = 0, binding = 0) uniform Frame {
    mat4 view;          // world -> eye (right-handed, camera looks down -z)
    mat4 proj;          // eye -> clip (Vulkan: y down, depth 0..1)
    vec4 viewport;      // width, height, 1/width, 1/height (pixels)
    vec4 pix_to_ray;    // D00, D02, D11, D12: eye ray through pixel (x,y) = (D00 x + D02, D11 y + D12, -1)
    vec4 depth_params;  // near, far, visibility epsilon (in splat radii), low-pass radius (pixels)
    vec4 tint_support;  // rgb (linear), strength
    vec4 tint_handle;   // rgb (linear), strength
    vec4 background;    // rgb (sRGB, written as is), alpha
    vec4 light;         // ambient, diffuse, specular, shininess
    vec4 misc;          // gaussian sharpness, 1/gamma, min weight, point-size threshold (pixels)
    uvec4 options;      // backface culling, apply gamma, display (0 shaded, 1 stretch heat map), -
    vec4 display;       // splat size scale, grey albedo (sRGB; < 0: the file's colours), EDL strength, EDL radius (pixels; resolve_edl.frag)
} F;

// Per-splat flag bits (renderer.py FLAG_*).
const uint FLAG_SUPPORT = 1u;
const uint FLAG_HANDLE = 2u;
const uint FLAG_DEFORMED = 4u;
const uint FLAG_INACTIVE = 8u;   // an inactive handle of several: drawn darker

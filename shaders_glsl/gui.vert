#version 450
// Dear ImGui vertices (ImDrawVert: pos2 float, uv2 float, col RGBA8 unorm) in
// framebuffer pixels -> clip space.  scale = 2 / display_size,
// translate = -1 - display_pos * scale (Vulkan's clip y points down, as ImGui's).
layout(push_constant) uniform GuiPush {
    vec2 scale;
    vec2 translate;
} pc;
layout(location = 0) in vec2 a_pos;
layout(location = 1) in vec2 a_uv;
layout(location = 2) in vec4 a_col;
layout(location = 0) out vec4 v_col;
layout(location = 1) out vec2 v_uv;
void main() {
    v_col = a_col;
    v_uv = a_uv;
    gl_Position = vec4(a_pos * pc.scale + pc.translate, 0.0, 1.0);
}

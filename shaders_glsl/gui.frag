#version 450
// Vertex colour times the bound texture (the font atlas or a user image);
// blended over the target with (SRC_ALPHA, ONE_MINUS_SRC_ALPHA).
layout(set = 0, binding = 0) uniform sampler2D u_tex;
layout(location = 0) in vec4 v_col;
layout(location = 1) in vec2 v_uv;
layout(location = 0) out vec4 o_color;
void main() {
    o_color = v_col * texture(u_tex, v_uv);
}

#version 450
layout(location = 0) out vec4 o_color;
void main() {
    o_color = vec4(0.5, 0.5, 0.5, 1.0);
}

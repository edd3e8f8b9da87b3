"""The Frame uniform block is declared once (splatedit.render.uniforms.FRAME_UBO)
and shaders_glsl/frame.glsl must agree with it member by member; the
display options it carries (splat size scale, grey shading) act on the image."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from splatedit.model.cloud import SplatCloud
from splatedit.render.camera import Camera
from splatedit.render.uniforms import FRAME_UBO, check_glsl_block, glsl_members, layout, parse_glsl_block
from tests.render.scenes import plane

FRAME_GLSL = Path(__file__).resolve().parents[2] / "shaders_glsl" / "frame.glsl"
W = H = 96


def test_frame_glsl_block_matches_the_dtype():
    text = FRAME_GLSL.read_text()
    assert check_glsl_block(text, "Frame", FRAME_UBO) == []
    assert [n for _, n, _ in parse_glsl_block(text, "Frame")] == list(FRAME_UBO.names)


def test_the_check_catches_a_reordered_or_retyped_member():
    text = FRAME_GLSL.read_text()
    swapped = text.replace("    vec4 tint_support;", "    vec4 TMP;").replace(
        "    vec4 tint_handle;", "    vec4 tint_support;").replace("    vec4 TMP;", "    vec4 tint_handle;")
    assert swapped != text and check_glsl_block(swapped, "Frame", FRAME_UBO)
    retyped = text.replace("    uvec4 options;", "    vec4 options;")
    assert any("options" in p for p in check_glsl_block(retyped, "Frame", FRAME_UBO))
    shorter = text.replace("    vec4 display;", "")
    assert check_glsl_block(shorter, "Frame", FRAME_UBO)


def test_std140_offsets_follow_the_glsl_rules():
    # a vec3 takes 12 bytes but aligns to 16: a float after it packs into its last 4 bytes
    src = "uniform B { vec3 a; float b; vec2 c; mat4 m; vec4 d; };"
    assert parse_glsl_block(src, "B") == [("vec3", "a", 0), ("float", "b", 12), ("vec2", "c", 16),
                                          ("mat4", "m", 32), ("vec4", "d", 96)]
    assert layout(FRAME_UBO)[-1] == ("vec4", "display", FRAME_UBO.itemsize - 16)
    assert "    uvec4 options;" in glsl_members(FRAME_UBO).splitlines()


def test_renderer_buffer_size_is_the_dtype_size():
    from splatedit.render import renderer
    assert renderer._UBO_BYTES == FRAME_UBO.itemsize


def _coverage(img):
    return float((img[..., :3].min(axis=2) < 250).mean())


@pytest.mark.parametrize("prepass", [True, False], ids=["prepass", "vertex"])
def test_splat_scale_grows_the_footprint_and_grey_lights_a_black_scan(renderer, prepass):
    base = plane(24, overlap=0.6)                   # sparse: gaps between the splats
    black = SplatCloud(base.positions, base.u, base.v, np.tile(np.array([[0, 0, 0, 255]], np.uint8), (base.n, 1)), name="black")
    cam = Camera(eye=(0.0, -0.4, 3.0), target=(0.0, 0.0, 0.0), fov_deg=45.0)
    saved = renderer.prepass, renderer.splat_scale, renderer.grey_shading
    try:
        renderer.prepass = prepass
        renderer.set_cloud(black)
        one = renderer.render(cam, W, H)
        renderer.splat_scale = 2.0
        two = renderer.render(cam, W, H)
        renderer.splat_scale = 1.0
        renderer.grey_shading = True
        grey = renderer.render(cam, W, H)
    finally:
        renderer.prepass, renderer.splat_scale, renderer.grey_shading = saved
    # overlap 0.6 leaves gaps; twice the axes close them (4x the area per splat)
    assert _coverage(two) > 1.4 * _coverage(one)
    fg = one[..., :3].min(axis=2) < 250
    assert one[fg, :3].mean() < 40                  # the file's colours: black
    assert grey[fg, :3].mean() > 120                # uniform grey shading: readable

"""GPU layouts are declared once (splatedit.render.uniforms: FRAME_UBO,
DEFORM_UBO, GS_FRAME_UBO, GS_GEOM, GS_REC) and every uniform / storage block
in shaders_glsl must agree with its dtype (std140 / std430 offsets, strides,
sizes) or be listed below as a plain array or as not yet declared; the CPU
packing through the dtypes writes the same bytes as the hand-offset packing
it replaced; the display options of the frame block act on the image."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from splatedit.model.cloud import SplatCloud
from splatedit.render.camera import Camera
from splatedit.render.uniforms import (BASIS_GROUP, CRAST_PUSH, DEFORM_UBO, DETAIL_ROW, FRAME_UBO, GS_FRAME_UBO,
                                       GS_GEOM, GS_PREP_PUSH, GS_REC, GS_SORT_PUSH, GUI_PUSH, MAX_GROUPS, PREP_PUSH,
                                       PREPARED_PUSH, RADIX_PUSH, TILE_PUSH,
                                       SPLAT_GEOM, SPLAT_REC_A, SPLAT_REC_B, check_glsl_block, check_glsl_records,
                                       glsl_members, layout, parse_glsl_block)
from tests.render.scenes import plane

SHADERS = Path(__file__).resolve().parents[2] / "shaders_glsl"
FRAME_GLSL = SHADERS / "frame.glsl"

#: (file, block, dtype): blocks compared member by member
BLOCKS = [("frame.glsl", "Frame", FRAME_UBO), ("deform.glsl", "Deform", DEFORM_UBO),
          ("gs_common.glsl", "GsFrame", GS_FRAME_UBO), ("gs_prepare.comp", "Push", GS_PREP_PUSH),
          ("gs_sort.comp", "Push", GS_SORT_PUSH), ("prepare_cs.glsl", "Push", PREP_PUSH),
          ("prepared.vert", "Push", PREPARED_PUSH), ("gui.vert", "GuiPush", GUI_PUSH),
          ("gs_radix.glsl", "RadixPush", RADIX_PUSH), ("gs_tile.glsl", "TilePush", TILE_PUSH),
          ("splat_cs_raster.glsl", "Push", CRAST_PUSH)]
#: (file, block, record dtype, constant prefix): flat record buffers
RECORDS = [("gs_common.glsl", "GsGeom", GS_GEOM, "GEOM"), ("gs_common.glsl", "GsRec", GS_REC, "REC"),
           ("prepare_cs.glsl", "Geom", SPLAT_GEOM, "GEOM"), ("prepare_cs.glsl", "RecA", SPLAT_REC_A, "RECA"),
           ("prepare_cs.glsl", "RecB", SPLAT_REC_B, "RECB"), ("prepared.vert", "RecA", SPLAT_REC_A, "RECA"),
           ("prepared.vert", "RecB", SPLAT_REC_B, "RECB"), ("prepare_cs.glsl", "Basis", BASIS_GROUP, "BASIS"),
           ("gs_prepare.comp", "GsBasis", BASIS_GROUP, "BASIS"),
           ("splat_cs_raster.glsl", "RecA", SPLAT_REC_A, "RECA"), ("splat_cs_raster.glsl", "RecB", SPLAT_REC_B, "RECB")]
#: (file, block, row dtype): buffers of one vec4 row per item
ROWS = [("detail.glsl", "Detail", DETAIL_ROW)]
#: plain arrays of one value per item (block -> GLSL member type)
PLAIN = {"GsRest": "uint[]", "GsBasisRow": "uint[]", "GsBasis": "vec4[]", "GsKeys": "uint[]", "GsOrder": "uint[]",
         "GsDraws": "uint[4]", "GsFlags": "uint[]", "Colors": "uint[]", "Flags": "uint[]", "Basis": "vec4[]",
         "Draws": "uint[8]", "RCount": "uint[]", "RKeysIn": "uint[]", "RValsIn": "uint[]", "RKeysOut": "uint[]",
         "RValsOut": "uint[]", "RHist": "uint[]", "RArgs": "uint[4]", "BKeys": "uint[]", "BVals": "uint[]",
         "TPairKeys": "uint[]", "TPairVals": "uint[]", "TScan": "uint[]", "TRanges": "uvec2[]",
         "TSortArgs": "uint[4]", "VisMin": "uint64_t[]", "VisRead": "uvec2[]", "AccC": "vec4[]",
         "AccN": "vec4[]", "BigList": "uint[]", "TileBins": "uint[]"}


def _source(fname: str) -> str:
    """A shader with its ``#include`` files expanded (recursively)."""
    return re.sub(r'#include\s+"([^"]+)"', lambda m: _source(m.group(1)), (SHADERS / fname).read_text())
W = H = 96


def test_frame_glsl_block_matches_the_dtype():
    text = FRAME_GLSL.read_text()
    assert check_glsl_block(text, "Frame", FRAME_UBO) == []
    assert [n for _, n, _ in parse_glsl_block(text, "Frame")] == list(FRAME_UBO.names)


@pytest.mark.parametrize("fname, block, dtype", BLOCKS, ids=[f"{b[0]}:{b[1]}" for b in BLOCKS])
def test_glsl_block_matches_its_dtype(fname, block, dtype):
    assert check_glsl_block((SHADERS / fname).read_text(), block, dtype) == []


@pytest.mark.parametrize("fname, block, dtype, prefix", RECORDS, ids=[f"{r[0]}:{r[1]}" for r in RECORDS])
def test_record_buffer_constants_match_the_dtype(fname, block, dtype, prefix):
    text = _source(fname)
    assert check_glsl_records(text, block, dtype, prefix) == []
    moved = text.replace(f"const uint {prefix}_STRIDE = ", f"const uint {prefix}_STRIDE = 1u + ")
    assert any("STRIDE" in p for p in check_glsl_records(moved, block, dtype, prefix))
    last = dtype.names[-1].upper()
    shifted = re.sub(rf"(const uint {prefix}_{last} = )(\d+)u;", lambda m: f"{m.group(1)}{int(m.group(2)) + 1}u;", text)
    assert shifted != text and any(last in p for p in check_glsl_records(shifted, block, dtype, prefix))


def test_record_check_catches_a_field_of_the_wrong_scalar_type():
    text = _source("prepare_cs.glsl")
    as_float = np.dtype([(n, "<f4", SPLAT_REC_B.fields[n][0].shape) for n in SPLAT_REC_B.names])
    assert any("not made of uint" in p for p in check_glsl_records(text, "RecB", as_float, "RECB"))


def test_every_glsl_block_is_declared_or_listed():
    seen = [(f.name, block) for f in sorted(SHADERS.iterdir())
            for block in re.findall(r"\b(?:uniform|buffer)\s+(\w+)\s*\{", f.read_text())]
    listed = {(f, b) for f, b, *_ in BLOCKS + RECORDS + ROWS}
    missing = [(f, b) for f, b in seen if (f, b) not in listed and b not in PLAIN]
    assert not missing, f"GLSL blocks with no declared dtype: {missing}"
    assert {(f, b) for f, b, *_ in BLOCKS + ROWS} <= set(seen) and set(PLAIN) <= {b for _, b in seen}
    for f, block in seen:
        if block in PLAIN:
            assert [m[0] for m in parse_glsl_block((SHADERS / f).read_text(), block)] == [PLAIN[block]], block


@pytest.mark.parametrize("fname, block, dtype", ROWS, ids=[r[1] for r in ROWS])
def test_row_buffers_hold_one_vec4_of_the_dtype_per_item(fname, block, dtype):
    assert [m[0] for m in parse_glsl_block(_source(fname), block)] == ["vec4[]"]
    assert dtype.itemsize == 16 and all(dtype.fields[f][0].base == np.float32 for f in dtype.names)


def test_the_deform_block_size_follows_the_basis_column_limit():
    text = (SHADERS / "deform.glsl").read_text()
    assert parse_glsl_block(text, "Deform")[-1] == ("vec4[%d]" % (4 * MAX_GROUPS), "rot", 48 * MAX_GROUPS)
    assert check_glsl_block(text.replace("MAX_BASIS_GROUPS = 4;", "MAX_BASIS_GROUPS = 5;"), "Deform", DEFORM_UBO)


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
    # std140 rounds array strides up to 16 bytes, std430 does not
    assert parse_glsl_block("layout(std140) uniform B { float a[3]; vec3 b; float c; };", "B") == [
        ("float[3]", "a", 0), ("vec3", "b", 48), ("float", "c", 60)]
    assert parse_glsl_block("layout(std430) buffer B { float a[3]; vec3 b; float c; };", "B") == [
        ("float[3]", "a", 0), ("vec3", "b", 16), ("float", "c", 28)]
    # a float[6] dtype field matches std430 but not std140 (stride 16)
    dt = np.dtype([("a", "<f4", (6,)), ("b", "<f4", (2,))])
    assert check_glsl_block("layout(std430) buffer B { float a[6]; vec2 b; };", "B", dt) == []
    assert check_glsl_block("layout(std140) uniform B { float a[6]; vec2 b; };", "B", dt)
    assert layout(FRAME_UBO)[-1] == ("vec4", "display", FRAME_UBO.itemsize - 16)
    assert "    uvec4 options;" in glsl_members(FRAME_UBO).splitlines()
    assert glsl_members(DEFORM_UBO).splitlines() == [f"    vec4 dC[{3 * MAX_GROUPS}];",
                                                     f"    vec4 rot[{4 * MAX_GROUPS}];"]


def test_renderer_buffer_size_is_the_dtype_size():
    from splatedit.render.splat import renderer
    assert renderer.UBO_BYTES == FRAME_UBO.itemsize


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

"""GPU uniform and storage layouts, declared once as numpy structured dtypes.

:data:`FRAME_UBO` is the per-frame uniform block ``Frame`` of
``shaders_glsl/frame.glsl`` (std140, set 0 binding 0): the renderer fills a
record of this dtype by field name (no hand offsets), and
:func:`check_glsl_block` compares the dtype with the GLSL block (member
names, types and std140 offsets; a test runs it on frame.glsl), so the two
cannot drift apart.  :func:`glsl_members` prints the GLSL members of a dtype
(to paste when adding a field).

Declared the same way: the deformation block ``Deform`` of deform.glsl
(:data:`DEFORM_UBO`), the Gaussian renderer's frame block ``GsFrame``
(:data:`GS_FRAME_UBO`) and per-Gaussian records (:data:`GS_GEOM`,
:data:`GS_REC`, gs_common.glsl), the splat renderer's per-splat geometry
and pre-pass records (:data:`SPLAT_GEOM`, :data:`SPLAT_REC_A`,
:data:`SPLAT_REC_B`, splat_records.glsl), the basis rows
(:data:`BASIS_GROUP`, deform.glsl), the detail rows (:data:`DETAIL_ROW`,
detail.glsl), the push-constant blocks (``*_PUSH``) and the GUI's vertex
(:data:`GUI_VERTEX`, Dear ImGui's ImDrawVert).  A uniform/storage block is compared member by member
(:func:`check_glsl_block`: std140 / std430 offsets, vec3 alignment, array
strides, block size); a buffer of flat ``float`` / ``vec4`` records is
compared through the GLSL constants naming its stride and field offsets
(:func:`check_glsl_records`), which the shaders index with.

A dtype is numpy's packed layout: a declaration only checks clean where that
equals the GLSL layout (vec4-sized members, or scalars / vec3 packed as std
allows); the check reports every member where it does not.
"""

from __future__ import annotations

import re

import numpy as np

from splatedit.tolerances import RENDER_MAX_BASIS_COLUMNS

#: the Frame block of shaders_glsl/frame.glsl.  mat4 fields hold the matrix
#: transposed (GLSL is column-major): ``rec["view"] = view.T``
FRAME_UBO = np.dtype([
    ("view", "<f4", (4, 4)),          # world -> eye
    ("proj", "<f4", (4, 4)),          # eye -> clip
    ("viewport", "<f4", (4,)),        # width, height, 1/width, 1/height
    ("pix_to_ray", "<f4", (4,)),      # D00, D02, D11, D12
    ("depth_params", "<f4", (4,)),    # near, far, visibility epsilon, low-pass radius
    ("tint_support", "<f4", (4,)),
    ("tint_handle", "<f4", (4,)),
    ("background", "<f4", (4,)),
    ("light", "<f4", (4,)),
    ("misc", "<f4", (4,)),            # sharpness, 1/gamma, min weight, point-size threshold
    ("options", "<u4", (4,)),         # culling, gamma, heat map, -
    ("display", "<f4", (4,)),         # splat size scale, grey albedo (< 0: file colours), -, -
])



#: groups of 4 basis columns (deform.glsl MAX_BASIS_GROUPS)
MAX_GROUPS = (RENDER_MAX_BASIS_COLUMNS + 3) // 4

#: the Deform block of shaders_glsl/deform.glsl (std140): dC of up to
#: 4 * MAX_GROUPS basis columns, rows dC[3g + i] = (dC_{4g..4g+3})[i] (GPU
#: units); rot[4g] = (unit axis, angle; 0 = none) of handle g, rot[4g + 1 + i]
#: = (D_0..D_3)[i] its frame offsets (GPU units)
DEFORM_UBO = np.dtype([
    ("dC", "<f4", (3 * MAX_GROUPS, 4)),
    ("rot", "<f4", (4 * MAX_GROUPS, 4)),
])

#: the GsFrame block of shaders_glsl/gs_common.glsl (std140); mat4 transposed
GS_FRAME_UBO = np.dtype([
    ("view", "<f4", (4, 4)),          # GPU model units -> eye
    ("focal", "<f4", (4,)),           # fx, fy (pixels), cx, cy (principal point, pixels)
    ("viewport", "<f4", (4,)),        # width, height, near, far (GPU units)
    ("eye", "<f4", (4,)),             # camera position (GPU units), SH degree
    ("limits", "<f4", (4,)),          # frustum clamp x/z, y/z, low-pass (px^2), alpha floor
    ("params", "<f4", (4,)),          # alpha ceiling, pick min opacity, pick sigmas^2, near cull distance
    ("background", "<f4", (4,)),      # rgb, -
    ("counts", "<u4", (4,)),          # n, uints of SH bands 1-3 per Gaussian, sort length, sRGB target
    ("tint_support", "<f4", (4,)),
    ("tint_handle", "<f4", (4,)),
    ("display", "<f4", (4,)),         # splat scale, grey, heat map, -
])

#: one Gaussian of the GsGeom buffer (``float geom[]``, gs_common.glsl GEOM_*
#: constants): centre relative to the origin (GPU units), opacity, covariance
#: xx xy xz yy yz zz (GPU units^2), SH DC rgb, unit shortest axis
GS_GEOM = np.dtype([
    ("center", "<f4", (3,)),
    ("opacity", "<f4"),
    ("cov", "<f4", (6,)),
    ("sh_dc", "<f4", (3,)),
    ("normal", "<f4", (3,)),
])

#: one Gaussian of the GsRec buffer (``vec4 rec[]``, written by
#: gs_prepare.comp, read by gs.vert; gs_common.glsl REC_* constants)
GS_REC = np.dtype([
    ("center", "<f4", (4,)),          # px x, px y, ndc depth, opacity
    ("conic", "<f4", (4,)),           # conic a b c, pick scale
    ("axes", "<f4", (4,)),            # half-axis 1 xy, half-axis 2 xy (pixels)
    ("color", "<f4", (4,)),           # rgb, index + 1 as bits
])

#: one splat of the splat renderer's geometry buffer (vertex buffer of the
#: vertex path; ``float geom[]`` of prepare_cs.glsl, GEOM_* constants in
#: splat_records.glsl): centre relative to the origin, axes u, v (GPU units)
SPLAT_GEOM = np.dtype([
    ("center", "<f4", (3,)),
    ("u", "<f4", (3,)),
    ("v", "<f4", (3,)),
])

#: one slot of the pre-pass record buffer A (``vec4 recA[]``, written by
#: prepare_cs.glsl, read by prepared.vert; RECA_* constants): the splat's
#: screen-space mapping rows (Splat.ms_cn, mt_tc, mw_r, splat_math.glsl)
SPLAT_REC_A = np.dtype([
    ("ms_cn", "<f4", (4,)),
    ("mt_tc", "<f4", (4,)),
    ("mw_r", "<f4", (4,)),
])

#: one slot of the pre-pass record buffer B (``uvec4 recB[]``, RECB_*
#: constants): center = (x, y, w float bits, splat index + 1); packed =
#: (quad low corner as 12.4 fixed-point pixels, or point size float bits;
#: quad high corner; rgba8 colour; octahedral normal as snorm 2x16)
SPLAT_REC_B = np.dtype([
    ("center", "<u4", (4,)),
    ("packed", "<u4", (4,)),
])

#: one row of the detail buffer (``vec4 detail[]``, detail.glsl): base normal
#: n_b (unit), offset lambda (GPU units) of a splat; zero for the others
DETAIL_ROW = np.dtype([
    ("normal", "<f4", (3,)),
    ("lam", "<f4"),
])

#: one group of 4 basis columns of a basis row (``vec4 basis[]`` of
#: prepare_cs.glsl / gs_common.glsl, the vertex path's ``in_basis``;
#: BASIS_* constants in deform.glsl): B, and its gradient x, y, z (per GPU
#: unit) of the 4 columns; a row is G such records
BASIS_GROUP = np.dtype([
    ("B", "<f4", (4,)),
    ("Bx", "<f4", (4,)),
    ("By", "<f4", (4,)),
    ("Bz", "<f4", (4,)),
])

#: push constants (std430) of gs_prepare.comp: basis groups per row, polar
#: iterations, compact (1: append the visible keys for the GPU radix sort)
GS_PREP_PUSH = np.dtype([("groups", "<u4"), ("polar_iterations", "<u4"), ("compact", "<u4")])
#: push constants of gs_sort.comp: bitonic stage k, step j, sort length n (a power of two)
GS_SORT_PUSH = np.dtype([("k", "<u4"), ("j", "<u4"), ("n", "<u4")])
#: push constants of the radix sort (gs_radix.glsl): digit shift, index of the
#: count in the count buffer, capacity of the buffers
RADIX_PUSH = np.dtype([("shift", "<u4"), ("count_index", "<u4"), ("capacity", "<u4"), ("pad", "<u4")])
#: push constants of the tile rasterizer (gs_tile.glsl): pair capacity, tiles
#: per row, tile rows, the transmittance where blending stops
TILE_PUSH = np.dtype([("capacity", "<u4"), ("tiles_x", "<u4"), ("tiles_y", "<u4"), ("t_min", "<f4")])
#: push constants of prepare_cs.glsl: basis window (base, count), record slots
#: n, first splat wbase of the per-splat window
PREP_PUSH = np.dtype([("base", "<u4"), ("count", "<u4"), ("n", "<u4"), ("wbase", "<u4")])
#: push constants of prepared.vert: record slots
PREPARED_PUSH = np.dtype([("n", "<u4")])
#: push constants of the compute rasterizer (splat_cs_raster.glsl): record
#: slots, mode (0 per splat, 1 the big-splat list), workgroups of mode 1,
#: the pixel count above which a splat goes to the list
CRAST_PUSH = np.dtype([("n", "<u4"), ("mode", "<u4"), ("groups", "<u4"), ("big_pixels", "<u4")])
#: push constants of gui.vert: pixels -> NDC scale and translation
GUI_PUSH = np.dtype([("scale", "<f4", (2,)), ("translate", "<f4", (2,))])
#: one vertex of the GUI's vertex buffer: Dear ImGui's ImDrawVert, copied
#: verbatim from its draw lists (gui.vert inputs 0-2): position (framebuffer
#: pixels), texture coordinate, RGBA8 unorm colour
GUI_VERTEX = np.dtype([("pos", "<f4", (2,)), ("uv", "<f4", (2,)), ("col", "u1", (4,))])

_BASES = {"f": "float", "u": "uint", "i": "int"}
_VEC = {"float": "vec", "uint": "uvec", "int": "ivec"}


def _glsl_type(base: str, shape: tuple) -> str:
    """GLSL type of a numpy field (base type, shape): () scalar, (n,) n <= 4
    vecn, (4, 4) mat4, (k, 4) vec4[k], (k,) k > 4 scalar[k], (k, 4, 4) mat4[k]."""
    dt = np.dtype(base)
    if dt.kind not in _BASES or dt.itemsize != 4:
        raise ValueError(f"no GLSL type for {base} {shape}")
    scalar = _BASES[dt.kind]
    shape = tuple(shape)
    if shape == ():
        return scalar
    if shape == (4, 4) and scalar == "float":
        return "mat4"
    if len(shape) == 1:
        return f"{_VEC[scalar]}{shape[0]}" if 2 <= shape[0] <= 4 else f"{scalar}[{shape[0]}]"
    if len(shape) == 2 and 2 <= shape[1] <= 4:
        return f"{_VEC[scalar]}{shape[1]}[{shape[0]}]"
    if len(shape) == 3 and shape[1:] == (4, 4) and scalar == "float":
        return f"mat4[{shape[0]}]"
    raise ValueError(f"no GLSL type for {base} {shape}")


def _fields(dtype: np.dtype) -> list[tuple[str, str, int, int]]:
    """``(glsl type, name, byte offset, byte size)`` of each field of ``dtype``."""
    out = []
    for name in dtype.names:
        sub, off = dtype.fields[name][:2]
        out.append((_glsl_type(sub.base.str, sub.shape), name, int(off), int(sub.itemsize)))
    return out


def layout(dtype: np.dtype) -> list[tuple[str, str, int]]:
    """``(glsl type, name, byte offset)`` of each field of ``dtype``."""
    return [f[:3] for f in _fields(dtype)]


def glsl_members(dtype: np.dtype) -> str:
    """The GLSL member declarations of ``dtype`` (one per line)."""
    out = []
    for t, n, _ in layout(dtype):
        base, _, count = t.partition("[")
        out.append(f"    {base} {n}{'[' + count if count else ''};")
    return "\n".join(out)


def _strip_comments(text: str) -> str:
    return re.sub(r"//[^\n]*", "", re.sub(r"/\*.*?\*/", "", text, flags=re.S))


def glsl_constants(text: str) -> dict[str, int]:
    """Integer ``const int|uint NAME = V;`` declarations of GLSL source ``text``
    (values may use earlier constants, + - * and parentheses)."""
    out: dict[str, int] = {}
    for name, expr in re.findall(r"\bconst\s+(?:int|uint)\s+(\w+)\s*=\s*([^;]+);", _strip_comments(text)):
        try:
            out[name] = _int_expr(expr, out)
        except ValueError:
            continue                        # not a plain integer expression
    return out


def _int_expr(expr: str, consts: dict[str, int]) -> int:
    e = re.sub(r"\b(\d+)[uU]\b", r"\1", expr.strip())
    e = re.sub(r"\b[A-Za-z_]\w*\b", lambda m: str(consts[m.group(0)]) if m.group(0) in consts else "?", e)
    if not re.fullmatch(r"[\d\s+\-*()]+", e):
        raise ValueError(f"not an integer constant expression: {expr.strip()!r}")
    return int(eval(e, {"__builtins__": {}}, {}))      # digits and + - * ( ) only


#: (alignment, size) in bytes of the non-array GLSL types (same in std140 and std430)
_ALIGN_SIZE = {"float": (4, 4), "int": (4, 4), "uint": (4, 4), "bool": (4, 4),
               "vec2": (8, 8), "uvec2": (8, 8), "ivec2": (8, 8),
               "vec3": (16, 12), "uvec3": (16, 12), "ivec3": (16, 12),
               "vec4": (16, 16), "uvec4": (16, 16), "ivec4": (16, 16), "mat4": (16, 64),
               "uint64_t": (8, 8)}


def _round(x: int, a: int) -> int:
    return (x + a - 1) // a * a


def _parse(text: str, block: str) -> tuple[str, list[tuple[str, str, int, int | None]], int | None]:
    """(packing, members (type, name, offset, size; None for a runtime array),
    block size or None) of uniform / buffer block ``block`` in ``text``."""
    src = _strip_comments(text)
    m = re.search(r"layout\s*\(([^)]*)\)[^{;]*?\b(?:uniform|buffer)\s+" + re.escape(block) + r"\s*\{(.*?)\}",
                  src, flags=re.S)
    if m is None:
        m = re.search(r"()\b(?:uniform|buffer)\s+" + re.escape(block) + r"\s*\{(.*?)\}", src, flags=re.S)
    if m is None:
        raise ValueError(f"no uniform or buffer block {block!r}")
    packing = "std430" if "std430" in m.group(1) or "push_constant" in m.group(1) else "std140"
    consts = glsl_constants(text)
    out, off, max_align = [], 0, 16 if packing == "std140" else 4
    for decl in m.group(2).split(";"):
        decl = decl.strip()
        if not decl:
            continue
        dm = re.fullmatch(r"(\w+)\s+(\w+)\s*(?:\[([^\]]*)\])?", decl)
        if dm is None:
            raise ValueError(f"member {decl!r} is not handled")
        typ, name, count = dm.groups()
        if typ not in _ALIGN_SIZE:
            raise ValueError(f"member {name}: type {typ} is not handled")
        align, size = _ALIGN_SIZE[typ]
        if count is not None:                       # array: stride = size rounded to the alignment
            if packing == "std140":
                align = _round(align, 16)
            stride = _round(size, align)
            n = None if count.strip() == "" else _int_expr(count, consts)
            typ, size = f"{typ}[{'' if n is None else n}]", None if n is None else n * stride
        off = _round(off, align)
        max_align = max(max_align, align)
        out.append((typ, name, off, size))
        off = off + (size or 0)
    total = None if out and out[-1][3] is None else _round(off, max_align)
    return packing, out, total


def parse_glsl_block(text: str, block: str) -> list[tuple[str, str, int]]:
    """``(type, name, byte offset)`` of the members of uniform or buffer block
    ``block`` in GLSL source ``text`` (comments ignored; std140 or std430 as
    its layout says: vec3 aligned to 16, std140 arrays strided by 16; an array
    type reads ``vec4[12]``, a runtime array ``float[]``)."""
    return [mem[:3] for mem in _parse(text, block)[1]]


def check_glsl_block(text: str, block: str, dtype: np.dtype) -> list[str]:
    """Differences between the GLSL block and ``dtype``: member types, names,
    offsets and sizes (array strides), and the block's size (empty: they agree)."""
    _, glsl, total = _parse(text, block)
    ours = _fields(dtype)
    problems = []
    for i in range(max(len(glsl), len(ours))):
        g = glsl[i] if i < len(glsl) else None
        o = ours[i] if i < len(ours) else None
        if g != o:
            problems.append(f"member {i}: GLSL {g} != dtype {o} (type, name, offset, size)")
    if not problems and total is not None and total != dtype.itemsize:
        problems.append(f"block size: GLSL {total} != dtype {dtype.itemsize}")
    return problems


def check_glsl_records(text: str, block: str, dtype: np.dtype, prefix: str) -> list[str]:
    """Differences between a buffer of flat records (the block's single member
    a runtime array of ``float`` / ``uint`` / ``vec4``) and the record dtype:
    the GLSL constants ``<prefix>_STRIDE`` (elements per record) and
    ``<prefix>_<FIELD>`` (element offset of each field) must equal the
    dtype's, and each field must be made of the element's scalar type."""
    _, glsl, _ = _parse(text, block)
    problems = []
    if len(glsl) != 1 or not glsl[0][0].endswith("[]"):
        return [f"block {block}: expected one runtime array member, got {[g[:2] for g in glsl]}"]
    elem = glsl[0][0][:-2]
    esize = _ALIGN_SIZE[elem][1]
    scalar = "uint" if elem.startswith("u") else "int" if elem.startswith("i") else "float"
    consts = {k[len(prefix) + 1:]: v for k, v in glsl_constants(text).items() if k.startswith(prefix + "_")}
    want = {"STRIDE": dtype.itemsize // esize}
    if dtype.itemsize % esize:
        problems.append(f"record size {dtype.itemsize} is not a whole number of {elem} ({esize} bytes)")
    for t, name, off, _ in _fields(dtype):
        if _BASES.get(dtype.fields[name][0].base.kind) != scalar:
            problems.append(f"field {name}: {t} is not made of {scalar}")
        if off % esize:
            problems.append(f"field {name}: offset {off} is not on a {elem} boundary")
        want[name.upper()] = off // esize
    for k in sorted(set(want) | set(consts)):
        if want.get(k) != consts.get(k):
            problems.append(f"{prefix}_{k}: GLSL {consts.get(k)} != dtype {want.get(k)}")
    return problems

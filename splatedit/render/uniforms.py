"""GPU uniform layouts, declared once as numpy structured dtypes.

:data:`FRAME_UBO` is the per-frame uniform block ``Frame`` of
``shaders_glsl/frame.glsl`` (std140, set 0 binding 0): the renderer fills a
record of this dtype by field name (no hand offsets), and
:func:`check_glsl_block` compares the dtype with the GLSL block (member
names, types and std140 offsets; a test runs it on frame.glsl), so the two
cannot drift apart.  :func:`glsl_members` prints the GLSL members of a dtype
(to paste when adding a field).

Only members whose std140 layout equals numpy's packed layout are used
(vec4 / uvec4 / ivec4 / mat4 and arrays of them): every member is 16-byte
aligned and sized, so the dtype's offsets are the std140 offsets.
"""

from __future__ import annotations

import re

import numpy as np

#: GLSL type -> (numpy base type, shape)
GLSL_TYPES = {"vec4": ("<f4", (4,)), "uvec4": ("<u4", (4,)), "ivec4": ("<i4", (4,)), "mat4": ("<f4", (4, 4))}

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


def _glsl_type(base: str, shape: tuple) -> str:
    for name, (b, s) in GLSL_TYPES.items():
        if np.dtype(b) == np.dtype(base) and tuple(s) == tuple(shape):
            return name
    raise ValueError(f"no std140-safe GLSL type for {base} {shape}")


def layout(dtype: np.dtype) -> list[tuple[str, str, int]]:
    """``(glsl type, name, byte offset)`` of each field of ``dtype``."""
    out = []
    for name in dtype.names:
        sub, off = dtype.fields[name][:2]
        out.append((_glsl_type(sub.base.str, sub.shape), name, int(off)))
    return out


def glsl_members(dtype: np.dtype) -> str:
    """The GLSL member declarations of ``dtype`` (one per line)."""
    return "\n".join(f"    {t} {n};" for t, n, _ in layout(dtype))


_STD140 = {"float": (4, 4), "int": (4, 4), "uint": (4, 4), "vec2": (8, 8), "vec3": (16, 12), "vec4": (16, 16),
           "uvec4": (16, 16), "ivec4": (16, 16), "mat4": (16, 64)}


def parse_glsl_block(text: str, block: str) -> list[tuple[str, str, int]]:
    """``(type, name, std140 offset)`` of the members of uniform block ``block``
    in GLSL source ``text`` (comments ignored; scalar, vector and mat4 members)."""
    src = re.sub(r"//[^\n]*", "", re.sub(r"/\*.*?\*/", "", text, flags=re.S))
    m = re.search(r"uniform\s+" + re.escape(block) + r"\s*\{(.*?)\}", src, flags=re.S)
    if m is None:
        raise ValueError(f"no uniform block {block!r}")
    out, off = [], 0
    for decl in m.group(1).split(";"):
        decl = decl.strip()
        if not decl:
            continue
        typ, name = decl.split()
        if typ not in _STD140:
            raise ValueError(f"member {name}: type {typ} is not handled")
        align, size = _STD140[typ]
        off = (off + align - 1) // align * align
        out.append((typ, name, off))
        off += size
    return out


def check_glsl_block(text: str, block: str, dtype: np.dtype) -> list[str]:
    """Differences between the GLSL block and ``dtype`` (empty: they agree)."""
    glsl, ours = parse_glsl_block(text, block), layout(dtype)
    problems = []
    for i in range(max(len(glsl), len(ours))):
        g = glsl[i] if i < len(glsl) else None
        o = ours[i] if i < len(ours) else None
        if g != o:
            problems.append(f"member {i}: GLSL {g} != dtype {o}")
    return problems

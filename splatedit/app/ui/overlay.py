"""On-screen overlay: text panels, brush circle and gizmo, composited on the CPU.

This is the editor's fallback path (``SPLATEDIT_GUI=0``, or a swapchain
that cannot receive a blit); the default draws the same things with Dear
ImGui on the GPU (:mod:`splatedit.app.ui.gui_panels`,
:mod:`splatedit.app.ui.gui_overlay`).  The original choice for a keyboard-only
editor: it needs a status panel, a help page, a text prompt and a few
lines -- no widgets.  Text is rasterised with Pillow (DejaVu Sans Mono when
installed, else Pillow's built-in font) into small RGBA *patches* cached by
content; each frame the patches are alpha-blended into the RGBA frame the
renderer returned, in numpy, only inside their bounding boxes (well under a
millisecond for a panel), and the result is presented.  No extra dependency,
no shader, no GPU pipeline to keep in sync with the renderer.
"""

from __future__ import annotations

import functools
import math
import os
from dataclasses import dataclass

import numpy as np
from PIL import Image, ImageDraw, ImageFont

_FONT_PATHS = ("/usr/share/fonts/truetype/dejavu/DejaVuSansMono.ttf",
               "/usr/share/fonts/dejavu/DejaVuSansMono.ttf",
               "/usr/share/fonts/TTF/DejaVuSansMono.ttf")

#: the paper's colours (Fig. 1): support blue, handle green
SUPPORT_RGB = (40, 90, 255)
HANDLE_RGB = (30, 200, 50)
AXIS_RGB = ((230, 60, 60), (60, 200, 60), (70, 110, 255))


@functools.lru_cache(maxsize=4)
def font(size: int = 14):
    for p in _FONT_PATHS:
        if os.path.exists(p):
            return ImageFont.truetype(p, size)
    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1
        return ImageFont.load_default()


@dataclass
class Patch:
    x: int
    y: int
    rgba: np.ndarray   # (h, w, 4) uint8, straight alpha

    @property
    def box(self) -> tuple[int, int, int, int]:
        h, w = self.rgba.shape[:2]
        return self.x, self.y, w, h


def blend(frame: np.ndarray, patch: Patch) -> None:
    """Alpha-blend ``patch`` into ``frame`` ((H, W, 4) uint8) in place."""
    H, W = frame.shape[:2]
    h, w = patch.rgba.shape[:2]
    x0, y0 = max(patch.x, 0), max(patch.y, 0)
    x1, y1 = min(patch.x + w, W), min(patch.y + h, H)
    if x1 <= x0 or y1 <= y0:
        return
    src = patch.rgba[y0 - patch.y:y1 - patch.y, x0 - patch.x:x1 - patch.x]
    dst = frame[y0:y1, x0:x1]
    a = src[..., 3:4].astype(np.uint16)
    if not a.any():
        return
    out = (src[..., :3].astype(np.uint16) * a + dst[..., :3].astype(np.uint16) * (255 - a) + 127) // 255
    dst[..., :3] = out.astype(np.uint8)


@functools.lru_cache(maxsize=64)
def text_panel(lines: tuple, size: int = 14, bg=(20, 22, 28, 200), fg=(235, 235, 235, 255),
               pad: int = 8, min_width: int = 0) -> np.ndarray:
    """An RGBA panel with ``lines`` of text (each a str or (str, rgb))."""
    f = font(size)
    asc, desc = f.getmetrics()
    lh = asc + desc + 2
    width = min_width
    for ln in lines:
        txt = ln if isinstance(ln, str) else ln[0]
        width = max(width, int(math.ceil(f.getlength(txt))))
    img = Image.new("RGBA", (width + 2 * pad, lh * len(lines) + 2 * pad), bg)
    d = ImageDraw.Draw(img)
    for i, ln in enumerate(lines):
        txt, col = (ln, fg) if isinstance(ln, str) else (ln[0], tuple(ln[1]) + (255,))
        d.text((pad, pad + i * lh), txt, font=f, fill=col)
    return np.asarray(img)


@functools.lru_cache(maxsize=32)
def ring(radius: int, rgb=(255, 255, 255), width: int = 2, halo: bool = True) -> np.ndarray:
    """An RGBA image of a circle outline (with a dark halo for contrast unless ``halo`` is False)."""
    r = int(radius)
    s = 2 * r + 2 * width + 4
    img = Image.new("RGBA", (s, s), (0, 0, 0, 0))
    d = ImageDraw.Draw(img)
    c = s / 2
    if halo:
        d.ellipse((c - r - 1, c - r - 1, c + r + 1, c + r + 1), outline=(0, 0, 0, 150), width=width + 2)
    d.ellipse((c - r, c - r, c + r, c + r), outline=tuple(rgb) + (230,), width=width)
    return np.asarray(img)


def line_patch(p0, p1, rgb, width: int = 2, dot: bool = False) -> Patch | None:
    """A straight line from pixel ``p0`` to ``p1`` (optionally a dot at p1)."""
    if not (np.isfinite(p0).all() and np.isfinite(p1).all()):
        return None
    x0, y0 = float(p0[0]), float(p0[1])
    x1, y1 = float(p1[0]), float(p1[1])
    if max(abs(x0), abs(y0), abs(x1), abs(y1)) > 1e5:
        return None
    m = width + 6
    bx, by = int(math.floor(min(x0, x1))) - m, int(math.floor(min(y0, y1))) - m
    w = int(math.ceil(abs(x1 - x0))) + 2 * m + 1
    h = int(math.ceil(abs(y1 - y0))) + 2 * m + 1
    img = Image.new("RGBA", (w, h), (0, 0, 0, 0))
    d = ImageDraw.Draw(img)
    d.line((x0 - bx, y0 - by, x1 - bx, y1 - by), fill=tuple(rgb) + (255,), width=width)
    if dot:
        d.ellipse((x1 - bx - 4, y1 - by - 4, x1 - bx + 4, y1 - by + 4), fill=tuple(rgb) + (255,))
    return Patch(bx, by, np.asarray(img))


def cross_patch(p, rgb=(255, 255, 255), size: int = 8) -> Patch:
    x, y = float(p[0]), float(p[1])
    s = size + 3
    img = Image.new("RGBA", (2 * s + 1, 2 * s + 1), (0, 0, 0, 0))
    d = ImageDraw.Draw(img)
    for col, w in (((0, 0, 0, 160), 4), (tuple(rgb) + (255,), 2)):
        d.line((s - size, s, s + size, s), fill=col, width=w)
        d.line((s, s - size, s, s + size), fill=col, width=w)
    return Patch(int(round(x)) - s, int(round(y)) - s, np.asarray(img))


def progress_bar(width: int, fraction: float, label: str, size: int = 14) -> np.ndarray:
    """A labelled progress bar panel."""
    f = font(size)
    asc, desc = f.getmetrics()
    h = asc + desc + 16
    img = Image.new("RGBA", (width, h + 14), (20, 22, 28, 220))
    d = ImageDraw.Draw(img)
    d.text((8, 6), label, font=f, fill=(235, 235, 235, 255))
    y = h - 2
    d.rectangle((8, y, width - 8, y + 8), outline=(200, 200, 200, 255))
    fx = 8 + int((width - 16) * min(max(fraction, 0.0), 1.0))
    d.rectangle((8, y, fx, y + 8), fill=(90, 160, 255, 255))
    return np.asarray(img)


def polyline_patch(points, rgb, width: int = 3, halo: bool = True) -> Patch | None:
    """A line strip through pixel ``points`` (m, 2), with a dark halo unless
    ``halo`` is False; NaN points break the strip."""
    p = np.asarray(points, float)
    ok = np.isfinite(p).all(axis=1) & (np.abs(p) < 1e5).all(axis=1) if len(p) else np.zeros(0, bool)
    if ok.sum() < 2:
        return None
    q = p[ok]
    m = width + 4
    bx, by = int(math.floor(q[:, 0].min())) - m, int(math.floor(q[:, 1].min())) - m
    w = int(math.ceil(q[:, 0].max())) - bx + m + 1
    h = int(math.ceil(q[:, 1].max())) - by + m + 1
    img = Image.new("RGBA", (w, h), (0, 0, 0, 0))
    d = ImageDraw.Draw(img)
    runs, cur = [], []
    for good, pt in zip(ok, p):
        if good:
            cur.append((float(pt[0]) - bx, float(pt[1]) - by))
        elif cur:
            runs.append(cur)
            cur = []
    if cur:
        runs.append(cur)
    layers = (((0, 0, 0, 140), width + 2),) if halo else ()
    for col, wd in layers + ((tuple(rgb) + (255,), width),):
        for r in runs:
            if len(r) >= 2:
                d.line(r, fill=col, width=wd, joint="curve")
    return Patch(bx, by, np.asarray(img))


def dot_patch(p, rgb, radius: int = 5, rim: bool = True) -> Patch:
    """A filled dot at pixel ``p``, with a dark outline unless ``rim`` is False."""
    x, y = float(p[0]), float(p[1])
    s = radius + 3
    img = Image.new("RGBA", (2 * s + 1, 2 * s + 1), (0, 0, 0, 0))
    d = ImageDraw.Draw(img)
    if rim:
        d.ellipse((s - radius - 1, s - radius - 1, s + radius + 1, s + radius + 1), fill=(0, 0, 0, 200))
    d.ellipse((s - radius, s - radius, s + radius, s + radius), fill=tuple(rgb) + (255,))
    return Patch(int(round(x)) - s, int(round(y)) - s, np.asarray(img))


#: panel colours of the distortion line: within the warn threshold / above it
DISTORTION_OK_RGB = (235, 235, 235)
DISTORTION_WARN_RGB = (255, 110, 90)


def distortion_lines(stats, heat_map: bool, source: str = "") -> list:
    """Panel lines of the distortion feedback: ``stretch max N.Nx, K > 3x``
    for the current pose (``stats``: a DistortionStats or None when nothing
    is moved), red when splats exceed the warn threshold; ``source`` names
    the committed edit they belong to when no move is live (see
    :func:`distortion_source`); plus the heat-map legend while it is shown."""
    out = []
    if stats is not None:
        text = (f"stretch max {stats.max_stretch:.1f}x, {stats.n_above_warn:,} > {stats.warn:g}x"
                f"   area x{stats.min_area_change:.2f}..{stats.max_area_change:.2f}")
        out.append((text, DISTORTION_WARN_RGB if stats.exceeds_warn else DISTORTION_OK_RGB))
        if source:
            out.append((source, DISTORTION_OK_RGB))
    if heat_map:
        out.append(("heat map (D): 1x grey  1.5x yellow  2x orange  3x red  4x+ dark red", (255, 200, 120)))
    return out


def distortion_source(session) -> str:
    """Which edit the distortion figures (and the heat map) show when no
    move is live: ``of edit 3: Grab 0.12 (until the next change)``; "" for
    the live pose or when there is none."""
    last = session.shown_edit()
    dc = session.current_dc()
    if last is None or (dc is not None and dc.any()):
        return ""
    return f"of edit {last.number}: {last.label} (until the next change)"

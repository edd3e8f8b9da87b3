"""Backend-neutral overlay shapes of the tool protocol.

A tool's :meth:`~splatedit.app.tools.base.Tool.shapes` returns a list of
these (window pixels, x right, y down; colours ``rgb`` 0..255); one painter
per backend draws them: :func:`to_patches` for the CPU overlay
(:mod:`splatedit.app.ui.overlay` patches, composited on the frame) and
:func:`splatedit.app.ui.gui_overlay.draw_shapes` for the GPU path (ImGui draw
lists).  A tool so writes its overlay once and it draws alike in both.

Every shape has a ``layer``: :data:`UNDER` (under the other tools' shapes,
e.g. the last closure's highlight), :data:`OVER` (the default) or
:data:`TOP` (over the GUI's panels too, e.g. the live G/R/S readout).
:func:`in_draw_order` sorts a frame's shapes by layer, keeping each
layer's order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: layers, back to front
UNDER, OVER, TOP = 0, 1, 2
#: pixel coordinates beyond this are off any window (a point near the eye plane)
FAR_PX = 1e5
#: the dark box behind labels (rgb)
LABEL_BG = (20, 22, 28)


def drawable(*pts) -> bool:
    """Every point finite and within :data:`FAR_PX` of the window."""
    return all(np.isfinite(p).all() and np.abs(p).max() < FAR_PX for p in pts)


@dataclass(frozen=True)
class Polyline:
    """A line strip through ``points`` ((m, 2) pixels; NaN rows break it),
    ``width`` pixels; ``closed`` joins the last point to the first; ``halo``:
    a dark line 2 px wider under it (contrast on any background)."""
    points: np.ndarray
    rgb: tuple
    width: float = 2.0
    closed: bool = False
    halo: bool = True
    layer: int = OVER

    def strip(self) -> np.ndarray:
        """(m', 2) float: the points, the first repeated at the end when closed."""
        p = np.asarray(self.points, float).reshape(-1, 2)
        return np.vstack([p, p[:1]]) if self.closed and len(p) > 1 else p


@dataclass(frozen=True)
class Circle:
    """A circle outline of ``radius`` pixels about ``centre`` (2,), ``width``
    pixels; ``halo``: over a dark ring (contrast on any background)."""
    centre: tuple
    radius: float
    rgb: tuple
    width: float = 2.0
    halo: bool = True
    layer: int = OVER


@dataclass(frozen=True)
class Dot:
    """A filled disc of ``radius`` pixels at ``centre`` (2,); ``rim``: a 1 px
    dark outline."""
    centre: tuple
    rgb: tuple
    radius: float = 5.0
    rim: bool = True
    layer: int = OVER


@dataclass(frozen=True)
class Cross:
    """A ``+`` of half-size ``size`` pixels at ``centre`` (2,), over a dark shadow."""
    centre: tuple
    rgb: tuple
    size: float = 8.0
    layer: int = OVER


@dataclass(frozen=True)
class Label:
    """One line of ``text`` on a dark box (alpha ``bg_alpha``, its padding
    included) whose top-left is ``corner`` (2,); ``size``: the font size in
    pixels (the GPU path uses the GUI's font); ``keep_inside``: the box is
    moved to keep ``margin`` pixels from every window edge
    (:func:`place_inside`); ``name``: the painter reports where the box went
    under this name (the GUI's ``gui_rects``)."""
    corner: tuple
    text: str
    rgb: tuple
    size: int = 13
    bg_alpha: int = 200
    keep_inside: bool = False
    margin: float = 0.0
    name: str = ""
    layer: int = OVER


@dataclass(frozen=True)
class Points:
    """Small 3 x 3 pixel squares at ``points`` ((m, 2) pixels; non-finite
    rows and points off the window are skipped)."""
    points: np.ndarray
    rgb: tuple
    alpha: int = 220
    layer: int = UNDER


SHAPES = (Polyline, Circle, Dot, Cross, Label, Points)


def place_inside(x: float, y: float, box_w: float, box_h: float, w: int, h: int,
                 margin: float = 0.0) -> tuple[float, float]:
    """Top-left (x, y) of a ``box_w`` x ``box_h`` pixel box wanted at (x, y),
    moved so that it keeps ``margin`` pixels from every edge of a ``w`` x
    ``h`` window (a box wider than the window starts at the left margin)."""
    x = min(float(x), w - margin - box_w)
    y = min(float(y), h - margin - box_h)
    return max(x, margin), max(y, margin)


def in_draw_order(shapes) -> list:
    """``shapes`` sorted back to front by layer (stable); an object that is
    not a shape is an error."""
    shapes = list(shapes)
    for s in shapes:
        if not isinstance(s, SHAPES):
            raise TypeError(f"not an overlay shape: {s!r}")
    return sorted(shapes, key=lambda s: s.layer)


def to_patches(shapes, size: tuple[int, int], record=None) -> list:
    """The CPU painter: overlay patches (:class:`splatedit.app.ui.overlay.Patch`)
    of ``shapes`` in draw order, for a ``size`` (w, h) pixel window;
    ``record(name, (x, y, w, h))`` is told where named labels went."""
    from splatedit.app.ui import overlay as ov
    from splatedit.app.document.selection import points_patch
    w, h = size
    out = []
    for s in in_draw_order(shapes):
        p = None
        if isinstance(s, Polyline):
            p = ov.polyline_patch(s.strip(), s.rgb, width=max(int(round(s.width)), 1), halo=s.halo)
        elif isinstance(s, Circle):
            if drawable(s.centre):
                img = ov.ring(int(round(s.radius)), s.rgb, max(int(round(s.width)), 1), halo=s.halo)
                p = ov.Patch(int(round(s.centre[0])) - img.shape[1] // 2,
                             int(round(s.centre[1])) - img.shape[0] // 2, img)
        elif isinstance(s, Dot):
            if drawable(s.centre):
                p = ov.dot_patch(s.centre, s.rgb, int(round(s.radius)), rim=s.rim)
        elif isinstance(s, Cross):
            if drawable(s.centre):
                p = ov.cross_patch(s.centre, s.rgb, int(round(s.size)))
        elif isinstance(s, Label):
            img = ov.text_panel((s.text,), size=s.size, fg=tuple(s.rgb) + (255,), pad=2 if s.size < 13 else 3,
                                bg=LABEL_BG + (s.bg_alpha,))
            x, y = float(s.corner[0]), float(s.corner[1])
            if s.keep_inside:
                x, y = place_inside(x, y, img.shape[1], img.shape[0], w, h, s.margin)
            p = ov.Patch(int(x), int(y), img)
            if s.name and record is not None:
                record(s.name, (int(x), int(y), img.shape[1], img.shape[0]))
        elif isinstance(s, Points):
            p = points_patch(s.points, (w, h), s.rgb, s.alpha)
        if p is not None:
            out.append(p)
    return out

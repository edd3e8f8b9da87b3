"""The tools' overlays drawn on the GPU: ImGui draw-list primitives.

The GPU painter of the tool protocol (:func:`draw_shapes`): the tools'
backend-neutral shapes (:mod:`splatedit.app.tools.shapes`; the CPU fallback
paints the same list with :func:`splatedit.app.tools.shapes.to_patches`) are
emitted as lines, circles and text into ImGui's *background* draw list,
which the GUI pass draws under its windows, on top of the scene frame in
the swapchain image (shapes of the TOP layer, the live G/R/S readout, go to
the foreground list, over the panels): no pixels are composited on the CPU.
Called between ``Gui.new_frame`` and ``Gui.render``.  Also the modal text
boxes (file browser, error box).
"""

from __future__ import annotations

import numpy as np
from imgui_bundle import imgui

from splatedit.app.document import selection as seltools
from splatedit.app.tools.shapes import (FAR_PX, TOP, Circle, Cross, Dot, Label, Points, Polyline, in_draw_order,
                                        place_inside)
from splatedit.app.ui.panel import Box
from splatedit.tolerances import EDITOR_GUI_MAX_HIGHLIGHT_DOTS

_SHADOW = (0, 0, 0, 160)


def col(rgb, alpha: int = 255) -> int:
    """ImGui's packed colour of an (r, g, b) 0..255 triple."""
    return imgui.IM_COL32(int(rgb[0]), int(rgb[1]), int(rgb[2]), int(alpha))


def _ok(*pts) -> bool:
    return all(np.isfinite(p).all() and np.abs(p).max() < FAR_PX for p in pts)


def _v(p) -> imgui.ImVec2:
    return imgui.ImVec2(float(p[0]), float(p[1]))


def line(dl, p0, p1, rgb, width: float = 2.0, dot: bool = False) -> None:
    if not _ok(p0, p1):
        return
    dl.add_line(_v(p0), _v(p1), col(rgb), width)
    if dot:
        dl.add_circle_filled(_v(p1), 4.0, col(rgb))


def cross(dl, p, rgb, size: float = 8.0) -> None:
    if not _ok(p):
        return
    x, y = float(p[0]), float(p[1])
    for c, w in ((col(_SHADOW[:3], _SHADOW[3]), 4.0), (col(rgb), 2.0)):
        dl.add_line(imgui.ImVec2(x - size, y), imgui.ImVec2(x + size, y), c, w)
        dl.add_line(imgui.ImVec2(x, y - size), imgui.ImVec2(x, y + size), c, w)


def polyline(dl, px, rgb, width: float = 2.0) -> None:
    """A polyline through (m, 2) pixels, broken where a point is not finite."""
    run = []
    for q in np.asarray(px, float):
        if _ok(q):
            run.append(_v(q))
            continue
        if len(run) > 1:
            dl.add_polyline(run, col(rgb), thickness=float(width), flags=0)
        run = []
    if len(run) > 1:
        dl.add_polyline(run, col(rgb), thickness=float(width), flags=0)


def dot(dl, p, rgb, radius: float = 5.0) -> None:
    if _ok(p):
        dl.add_circle_filled(_v(p), radius + 1.0, col((0, 0, 0), 200))
        dl.add_circle_filled(_v(p), radius, col(rgb))


def label(dl, p, text: str, rgb, bg_alpha: int = 200) -> None:
    """``text`` on a dark box whose top-left is ``p``."""
    size = imgui.calc_text_size(text)
    x, y = float(p[0]), float(p[1])
    dl.add_rect_filled(imgui.ImVec2(x - 3, y - 2), imgui.ImVec2(x + size.x + 3, y + size.y + 2),
                       col((20, 22, 28), bg_alpha))
    dl.add_text(imgui.ImVec2(x, y), col(rgb), text)


def dots(dl, px, size: tuple[int, int], rgb=seltools.CLOSURE_RGB, alpha: int = 220) -> int:
    """Small squares at the (m, 2) pixels inside the window, one per distinct
    pixel (at most EDITOR_GUI_MAX_HIGHLIGHT_DOTS, evenly thinned); returns
    how many were drawn."""
    w, h = size
    px = np.asarray(px, float).reshape(-1, 2)
    p = np.floor(px[np.isfinite(px).all(axis=1)]).astype(np.int64)
    p = p[(p[:, 0] >= 0) & (p[:, 0] < w) & (p[:, 1] >= 0) & (p[:, 1] < h)]
    if not len(p):
        return 0
    p = np.unique(p[:, 1] * w + p[:, 0])
    if len(p) > EDITOR_GUI_MAX_HIGHLIGHT_DOTS:
        p = p[np.linspace(0, len(p) - 1, EDITOR_GUI_MAX_HIGHLIGHT_DOTS).astype(np.int64)]
    c = col(rgb, alpha)
    for k in p.tolist():
        x, y = k % w, k // w
        dl.add_rect_filled(imgui.ImVec2(x - 1, y - 1), imgui.ImVec2(x + 2, y + 2), c)
    return len(p)


# ------------------------------------------------------------------ tools
def draw_shapes(shapes, w: int, h: int, under=None, top=None, record=None) -> None:
    """The GPU painter: backend-neutral overlay shapes
    (:mod:`splatedit.app.tools.shapes`) as ImGui draw-list primitives, in draw
    order; layers UNDER and OVER into ``under`` (default: the background
    draw list, under the GUI's windows), TOP into ``top`` (default: the
    foreground list, over the panels); ``record(name, (x, y, w, h))`` is
    told where named labels went."""
    if under is None:
        under = imgui.get_background_draw_list()
    if top is None:
        top = imgui.get_foreground_draw_list()
    for s in in_draw_order(shapes):
        dl = top if s.layer == TOP else under
        if isinstance(s, Polyline):
            strip = s.strip()
            if s.halo:
                polyline(dl, strip, (0, 0, 0), s.width + 2.0)       # a dark halo, as the CPU path
            polyline(dl, strip, s.rgb, s.width)
        elif isinstance(s, Circle):
            if _ok(s.centre):
                c, r = _v(s.centre), float(s.radius)
                if s.halo:
                    dl.add_circle(c, r + 1.0, col((0, 0, 0), 150), 0, s.width + 2.0)
                    dl.add_circle(c, r, col(s.rgb, 230), 0, float(s.width))
                else:
                    dl.add_circle(c, r, col(s.rgb), 0, float(s.width))
        elif isinstance(s, Dot):
            if _ok(s.centre):
                if s.rim:
                    dl.add_circle_filled(_v(s.centre), s.radius + 1.0, col((0, 0, 0), 200))
                dl.add_circle_filled(_v(s.centre), float(s.radius), col(s.rgb))
        elif isinstance(s, Cross):
            cross(dl, s.centre, s.rgb, float(s.size))
        elif isinstance(s, Label):
            size = imgui.calc_text_size(s.text)
            bw, bh = size.x + 6, size.y + 4              # label()'s box: 3 / 2 pixels around the text
            x, y = float(s.corner[0]), float(s.corner[1])
            if s.keep_inside:
                x, y = place_inside(x, y, bw, bh, w, h, s.margin)
            label(dl, (x + 3, y + 2), s.text, s.rgb, s.bg_alpha)
            if s.name and record is not None:
                record(s.name, (int(x), int(y), int(round(bw)), int(round(bh))))
        elif isinstance(s, Points):
            dots(dl, s.points, (w, h), s.rgb, s.alpha)


def draw_tools(ed, w: int, h: int) -> None:
    """Every tool's overlay shapes of the frame (:meth:`Editor.overlay_shapes`);
    where named labels went (the readout) is recorded in the GUI's rects
    (the status file's ``gui_rects``)."""
    gui = getattr(ed, "gui", None)
    record = None if gui is None else (lambda name, b: gui.rects.__setitem__(name, Box(*b)))
    draw_shapes(ed.overlay_shapes(w, h), w, h, record=record)


def text_box(dl, lines, w: int, h: int, *, top: float | None = None, pad: int = 8,
             bg=(12, 16, 26), min_width: float = 0.0) -> tuple[int, int, int, int, int]:
    """Rows of coloured text [(text, rgb)] in a filled box centred in a
    ``w`` x ``h`` window (at ``top`` when given, else centred vertically), on
    the foreground draw list (over the panels; clicks are not taken by ImGui,
    so the editor's own hit tests apply).  Returns (x, y, box w, box h, line height)."""
    lh = int(imgui.get_text_line_height_with_spacing())
    tw = max([imgui.calc_text_size(t).x for t, _ in lines] + [min_width])
    bw, bh = int(tw) + 2 * pad, lh * len(lines) + 2 * pad
    x = max((w - bw) // 2, 0)
    y = max((h - bh) // 2, 0) if top is None else int(min(max(top, 0), max(h - bh, 0)))
    dl.add_rect_filled(_v((x, y)), _v((x + bw, y + bh)), col(bg, 240), 4.0)
    for k, (text, rgb) in enumerate(lines):
        dl.add_text(_v((x + pad, y + pad + k * lh)), col(rgb), text)
    return x, y, bw, bh, lh


def draw_modal_boxes(ed, w: int, h: int, top: float) -> None:
    """The file browser (Ctrl+O) and the load/save error box, drawn like the
    CPU overlay draws them, with their hit rectangles recorded for clicks."""
    from splatedit.app.ui import panel
    dl = imgui.get_foreground_draw_list()
    b = ed.browser
    if b.shown:
        lh = int(imgui.get_text_line_height_with_spacing())
        x, y, bw, bh, lh = text_box(dl, b.lines(h, lh, 8), w, h, min_width=560)
        b.placed((x, y, bw, bh), 8, lh)
    if ed.error_box is None:
        ed.error_rect = None
    else:
        x, y, bw, bh, _ = text_box(dl, panel.error_lines(ed.error_box), w, h, top=top, bg=(70, 18, 18))
        ed.error_rect = (x, y, bw, bh)

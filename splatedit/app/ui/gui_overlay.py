"""The tools' overlays drawn on the GPU: ImGui draw-list shapes.

The same geometry as the CPU overlay (:mod:`splatedit.app.ui.overlay`, the
tools' ``overlay`` patches), taken from the tools (gizmo axes, rings and
scale circle, curve polyline and dots, brush ring, the last closure's
highlight, the live G/R/S readout), but emitted as lines, circles and text
into ImGui's *background* draw list, which the GUI pass draws under its
windows, on top of the scene frame in the swapchain image: no pixels are
composited on the CPU.  Called between ``Gui.new_frame`` and ``Gui.render``.
"""

from __future__ import annotations

import numpy as np
from imgui_bundle import imgui

from splatedit.app.ui import overlay as ov
from splatedit.app.tools.curve import CURVE_RGB
from splatedit.app.tools.gizmo import READOUT_RGB, readout_box
from splatedit.app.document import selection as seltools
from splatedit.app.tools.shapes import Polyline
from splatedit.app.ui.panel import Box
from splatedit.tolerances import EDITOR_GUI_MAX_HIGHLIGHT_DOTS

_SHADOW = (0, 0, 0, 160)
#: pixel coordinates beyond this are off any window (a point near the eye plane)
_FAR_PX = 1e5


def col(rgb, alpha: int = 255) -> int:
    """ImGui's packed colour of an (r, g, b) 0..255 triple."""
    return imgui.IM_COL32(int(rgb[0]), int(rgb[1]), int(rgb[2]), int(alpha))


def _ok(*pts) -> bool:
    return all(np.isfinite(p).all() and np.abs(p).max() < _FAR_PX for p in pts)


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
def draw_brush(ed, dl, w: int, h: int) -> None:
    """The closure highlight (under everything) and the brush ring with its mode tag."""
    s, b = ed.session, ed.brush
    hl = b.tools.highlighted(s.cloud)
    if hl is not None:
        px, d = ed.cam.project(s.cloud.positions[hl], w, h)
        dots(dl, np.where((d > 0)[:, None], px, np.nan), (w, h))
    if ed.drag.camera or s.manip is not None or ed.modal() or not ed.cursor_inside:
        return
    if ed.gui is not None and ed.gui.wants_mouse:
        return                      # the pointer is over a panel: no brush there
    rgb = b.cursor_colour()
    mx, my = ed.mouse
    r = float(b.radius)
    dl.add_circle(imgui.ImVec2(mx, my), r + 1.0, col((0, 0, 0), 150), 0, 4.0)
    dl.add_circle(imgui.ImVec2(mx, my), r, col(rgb, 230), 0, 2.0)
    tag = "3D" if b.tools.mode == seltools.BRUSH_3D else "VIS"
    k = r * 0.7071
    label(dl, (mx + k + 4, my + k + 4), tag, rgb, 150)


def draw_curve(ed, dl, w: int, h: int) -> None:
    s = ed.session
    poly = s.curve_polyline()
    if poly is not None:
        px, d = ed.cam.project(poly, w, h)
        px = np.array(px, float)
        px[np.asarray(d) <= 0] = np.nan
        polyline(dl, px, CURVE_RGB, 3.0)
    active = s.manip_target[1] if (s.manip_target and s.manip_target[0] == "curve") else None
    chosen = s.active_curve_point() if s.curve_mode else None     # the transform fields' point: ringed
    for j, q in enumerate(ed.curve.dots(w, h)):
        if j == chosen and j != active:
            dot(dl, q, (255, 255, 255), 7.0)
        dot(dl, q, (255, 255, 255) if j == active else CURVE_RGB, 7.0 if j == active else 5.0)


def draw_gizmo(ed, dl, w: int, h: int) -> None:
    """Inactive handles' crosses, the active handle's axes, rotation rings,
    scale circle, constraint axis and the pivot -> current line."""
    s, cam, gz = ed.session, ed.cam, ed.gizmo
    if len(s.selection.handles) > 1:
        for k, hm in enumerate(s.selection.handles):
            if k != s.selection.active and hm.any():
                px, d = cam.project(s.handle_centroid(k), w, h)
                if d[0] > 0:
                    cross(dl, px[0], (20, 90, 25), 6.0)
    if not s.selection.handle.any() or (s.manip_target and s.manip_target[0] == "curve"):
        return
    piv = gz.handle_centre()
    m = s.current_matrix()
    cur = m[:3, :3] @ piv + m[:3, 3]
    grip = gz.scale_circle(w, h)
    if grip is not None and _ok(grip[0]):
        dl.add_circle(_v(grip[0]), float(grip[1]), col((225, 225, 225)), 0, 1.0)
    for k, px in gz.rings(w, h):
        polyline(dl, px, ov.AXIS_RGB[k], 2.0)
    for k, p0, p1 in gz.axes(w, h):
        line(dl, p0, p1, ov.AXIS_RGB[k], 3.0, dot=True)
    px, depth = cam.project(np.vstack([piv, cur]), w, h)
    if depth.min() <= 0:
        return
    if s.manip is not None and s.manip.axis is not None:
        a = s.manip.axis_vector() * cam.scene_radius
        ends, d2 = cam.project(np.vstack([cur - a, cur + a]), w, h)
        if d2.min() > 0:
            line(dl, ends[0], ends[1], ov.AXIS_RGB[s.manip.axis], 1.0)
    if s.manip is not None:
        line(dl, px[0], px[1], (255, 255, 255), 1.0)
    cross(dl, px[1], ov.HANDLE_RGB if s.active_fitted() else (200, 200, 200))


def draw_readout(ed, dl, w: int, h: int) -> None:
    """The live distance / angle / factor next to the cursor while moving."""
    text = ed.gizmo.readout_text()
    if text is None:
        return
    size = imgui.calc_text_size(text)
    bw, bh = size.x + 6, size.y + 4              # label()'s box: 3 / 2 pixels around the text
    bx, by = readout_box(ed.mouse, bw, bh, w, h)
    label(dl, (bx + 3, by + 2), text, READOUT_RGB)
    gui = getattr(ed, "gui", None)
    if gui is not None:                          # where it is (the status file's gui_rects)
        gui.rects["readout"] = Box(int(bx), int(by), int(round(bw)), int(round(bh)))


def draw_shapes(dl, shapes) -> None:
    """Backend-neutral overlay shapes (:mod:`splatedit.app.tools.shapes`) as draw-list lines."""
    for s in shapes:
        if not isinstance(s, Polyline):
            raise TypeError(f"not an overlay shape: {s!r}")
        strip = s.strip()
        polyline(dl, strip, (0, 0, 0), s.width + 2.0)       # a dark halo, as the CPU path
        polyline(dl, strip, s.rgb, s.width)


def draw_tools(ed, w: int, h: int) -> None:
    """Every tool overlay of the frame into the background draw list."""
    if ed.session is None:
        return
    dl = imgui.get_background_draw_list()
    draw_brush(ed, dl, w, h)
    draw_curve(ed, dl, w, h)
    draw_gizmo(ed, dl, w, h)
    for tool in ed.tools:               # the protocol's shapes, painted on the GPU
        draw_shapes(dl, tool.shapes(w, h))
    draw_readout(ed, imgui.get_foreground_draw_list(), w, h)      # over the panels


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

"""The editor's text overlays: the status panel (its lines and where it goes:
never over the gizmo), the F1 help window (fits any window size: pages /
scrolls, never over the panel), progress bars and the centred questions."""

from __future__ import annotations

import time
from dataclasses import dataclass

from splatedit.app.ui import overlay as ov
from splatedit.app.tools.shapes import to_patches
from splatedit.app.document import selection as seltools
from splatedit.app.document.gaussian import model_summary
from splatedit.select.selection import SUPPORT
from splatedit.app.ui.keymap import help_lines
from splatedit.app.tools.curve import CURVE_RGB
from splatedit.tolerances import EDITOR_HELP_MARGIN_PX, EDITOR_HELP_PAGE_OVERLAP

PANEL_MARGIN = 8
HELP_TITLE_RGB = (140, 190, 255)
#: font sizes the help tries, largest first, to fit beside the panel
HELP_FONT_SIZES = (13, 12, 11)


@dataclass(frozen=True)
class Box:
    """A screen rectangle in pixels (x, y: top-left)."""
    x: int
    y: int
    w: int
    h: int

    def overlaps(self, other) -> bool:
        if other is None:
            return False
        x0, y0, x1, y1 = other
        return self.x < x1 and x0 < self.x + self.w and self.y < y1 and y0 < self.y + self.h

    @property
    def right(self) -> int:
        return self.x + self.w

    @property
    def bottom(self) -> int:
        return self.y + self.h


def place_panel(size: tuple[int, int], wh: tuple[int, int], avoid) -> Box:
    """Where the panel goes: the top-left corner, else the first other corner
    (top-right, bottom-left, bottom-right) that does not cover ``avoid``
    (the gizmo's box ``(x0, y0, x1, y1)`` or None)."""
    w, h = size
    pw, ph = wh
    m = PANEL_MARGIN
    corners = ((m, m), (w - pw - m, m), (m, h - ph - m), (w - pw - m, h - ph - m))
    for x, y in corners:
        b = Box(max(int(x), 0), max(int(y), 0), pw, ph)
        if not b.overlaps(avoid):
            return b
    return Box(m, m, pw, ph)


def panel_lines(ed) -> list:
    """The status panel's lines (str or (str, rgb))."""
    s = ed.session
    if s is None:
        return [f"splatedit - opening {ed.path}", "F1: help   Ctrl+O: open another model"]
    st = s.stats()
    brush = ed.brush
    lines = [f"{ed.cloud_name}   {model_summary(s.cloud)}"]
    if getattr(ed, "ooc", None) is not None:
        lines.append(ed.ooc.summary(s))
    tgt = "SUPPORT" if s.brush_target == SUPPORT else "HANDLE"
    erase = "  ERASE" if brush.erase_toggle else ""
    mode = "3D" if brush.mode == seltools.BRUSH_3D else "VISIBLE"
    lines.append((f"brush: {tgt} {mode}{erase}  radius {brush.radius:.0f} px   (Tab, V, E, [ ])",
                  ov.SUPPORT_RGB if s.brush_target == SUPPORT else ov.HANDLE_RGB))
    note = brush.mode_note()
    if note:
        lines.append((note, (255, 230, 120)))
    for tool in ed.tools:           # the protocol tools' state lines
        line = tool.status()
        if line:
            lines.append((line, (255, 230, 120)))
    lines.append(f"support {st.support:,}   handle {st.handle:,}   "
                 f"deformation {s.deformation.value.upper()} (B)")
    hs = s.selection.handles
    if len(hs) > 1 or s.curve_points or s.curve_mode:
        sizes = " ".join(f"[{n:,}]" if k == s.selection.active else f"{n:,}"
                         for k, n in enumerate(st.handle_sizes))
        tool = " K:ON" if s.curve_mode else ""
        lines.append((f"handles {len(hs)}: {sizes}   curve {st.curve_points} pts{tool}   "
                      f"columns {st.columns}/16", CURVE_RGB if s.curve_mode else (235, 235, 235)))
    if s.pose_pending and s.manip is None and not s.committing:
        lines.append(("pending moves: Enter applies them as one edit, Esc discards", (255, 230, 120)))
    fit, prog = st.fit, st.progress
    if st.commit is not None:
        c = st.commit
        lines.append((f"edit: {c.stage} {c.fraction * 100:.0f}% ({c.elapsed:.1f} s)", (255, 230, 120)))
    elif prog is not None:
        lines.append(f"solver: {prog.stage} {prog.fraction * 100:.0f}% ({prog.elapsed:.1f} s)")
    elif fit is not None:
        lines.append(f"solver: {fit.method}, {fit.centers} centers / {fit.constraints} "
                     f"constraints, residual {fit.residual:.1e}")
        lines.append(f"        precompute {fit.fit_seconds:.2f} s fit + {fit.basis_seconds:.2f} s basis")
    elif st.error:
        lines.append((f"solver: {st.error[:90]}", (255, 120, 120)))
    else:
        lines.append("solver: paint a support (1) then a handle (2)")
    if s.manip is not None:
        lines.append((s.manip.describe(), (255, 230, 120)))
    lines += ov.distortion_lines(s.distortion(), ed.viewport.distortion_map, ov.distortion_source(s))
    vp = ed.viewport
    up = ed.camera.up
    if up.label != "+Y" or vp.grey or vp.splat_scale != 1.0:     # only when not the defaults
        lines.append(f"view: up {up.label} ({up.source.value})" + ("  grey shading" if vp.grey else "")
                     + (f"  splats {vp.splat_scale:.2f}x" if vp.splat_scale != 1.0 else "") + "   (U, M, Shift+[ ])")
    info = vp.last_info
    if info is not None:
        what = f"{info.splats:,} {'Gaussians' if info.gaussians else 'splats'}" + (" LOD" if info.lod else "") + (f" 1/{info.div} res" if info.div > 1 else "")
        lines.append(f"frame: render {info.ms:.0f} ms ({what}), total {ed.frame_ms:.0f} ms")
    lines.append(f"edits {len(s.edits)}{'  unsaved' if s.dirty else ''}   undo {s.history.position}"
                 f"/{len(s.history) - 1}")
    if ed.message and time.perf_counter() - ed.message_time < 8:
        lines.append((ed.message[:100], (255, 220, 140)))
    lines.append("F1: help   Ctrl+O: open a model   P: hide this panel")
    return lines


class HelpView:
    """The F1 help window: the keymap's help lines, paged to fit the space
    left by the panel (beside it when wide enough, else below it, else the
    whole window with the panel hidden while the help is open)."""

    def __init__(self):
        self.shown = False
        self.top = 0                 # first line shown
        self.rows = 0                # lines that fit (last layout)
        self.box: Box | None = None
        self.covers_panel = False    # the window is too small for both: the panel steps aside
        #: the help's rows, (text, rgb) (:func:`~splatedit.app.ui.keymap.help_lines`)
        self.lines = help_lines()
        self._cache = None

    @property
    def total(self) -> int:
        return len(self.lines)

    def toggle(self) -> None:
        self.shown = not self.shown
        self.top = 0

    def scroll(self, lines: int) -> None:
        self.top = int(min(max(self.top + lines, 0), max(self.total - max(self.rows, 1), 0)))

    def page(self, direction: int) -> None:
        self.scroll(direction * max(self.rows - EDITOR_HELP_PAGE_OVERLAP, 1))

    def _measure(self, size: int) -> tuple[int, int]:
        f = ov.font(size)
        asc, desc = f.getmetrics()
        width = max(int(f.getlength(t)) + 1 for t, _ in self.lines)
        return width + 16, asc + desc + 2

    def layout(self, win: tuple[int, int], panel: Box | None) -> tuple[Box, int, int]:
        """``(box, font size, rows)`` of the help in a window of size ``win``
        beside / below ``panel`` (None: no panel)."""
        w, h = win
        m = EDITOR_HELP_MARGIN_PX
        self.covers_panel = False
        areas = []
        if panel is not None:
            areas.append(Box(panel.right + m, m, w - panel.right - 2 * m, h - 2 * m))     # beside
            areas.append(Box(m, panel.bottom + m, w - 2 * m, h - panel.bottom - 2 * m))   # below
        areas.append(Box(m, m, w - 2 * m, h - 2 * m))                                     # whole window
        for i, area in enumerate(areas):
            last = i == len(areas) - 1
            for size in HELP_FONT_SIZES:
                tw, lh = self._measure(size)
                rows = (area.h - 16) // lh - 1          # one line for the footer
                if (tw <= area.w or last and size == HELP_FONT_SIZES[-1]) and (rows >= 8 or last):
                    rows = max(min(rows, self.total), 1)
                    bw = min(tw, max(area.w, 1))
                    bh = min((rows + 1) * lh + 16, max(area.h, 1))
                    x = area.x + max((area.w - bw) // 2, 0) if i > 0 else area.x
                    self.covers_panel = panel is not None and last
                    return Box(x, area.y, bw, bh), size, rows
        raise AssertionError("unreachable")

    def patch(self, win: tuple[int, int], panel: Box | None) -> ov.Patch | None:
        if not self.shown:
            return None
        box, size, rows = self.layout(win, panel)
        self.rows = rows
        self.scroll(0)                     # keep top in range after a resize
        key = (box, size, rows, self.top)
        if self._cache is None or self._cache[0] != key:
            shown = self.lines[self.top:self.top + rows]
            lines = [(t, HELP_TITLE_RGB) if title else t for t, title in shown]
            end = self.top + len(shown)
            more = "PageDown / PageUp, arrows or wheel: scroll   " if rows < self.total else ""
            lines.append((f"lines {self.top + 1}-{end} of {self.total}   {more}F1 / Esc: close", (255, 220, 140)))
            img = ov.text_panel(tuple(lines), size=size, bg=(10, 12, 18, 235))
            img = img[:box.h, :box.w]
            self._cache = (key, ov.Patch(box.x, box.y, img))
        self.box = Box(box.x, box.y, self._cache[1].rgba.shape[1], self._cache[1].rgba.shape[0])
        return self._cache[1]


ERROR_BOX_RGB = (255, 150, 140)
#: the error box's widest line in characters (longer messages wrap)
ERROR_BOX_CHARS = 100


def error_lines(message: str) -> list:
    """The error box's rows [(text, rgb)]: a title, the wrapped message, how to close it."""
    import textwrap
    lines = [("Error", ERROR_BOX_RGB)]
    lines += [(t, (245, 235, 235)) for t in textwrap.wrap(message, ERROR_BOX_CHARS)[:8]]
    lines.append(("Esc, Enter or a click here: close", (200, 200, 200)))
    return lines


def restore_question(ed) -> tuple | None:
    """The question at start when a recovery copy exists (rows), or None."""
    guard = getattr(ed, "crash_guard", None)
    e = None if guard is None else guard.confirm_restore
    if e is None:
        return None
    return (f"Recover unsaved work: {e.name} ({e.edits} edit(s), {e.when()})",
            "Y: restore it     N: discard it     Esc: ask again next time",
            f"(kept in {e.manifest.parent})")


def open_question(ed) -> tuple | None:
    """The unsaved-changes question before opening another model (rows), or None."""
    if ed.confirm_open is None:
        return None
    return ("Unsaved changes.", f"Y: open {ed.confirm_open.name} without saving     N / Esc: keep editing",
            "(Ctrl+S saves)")


def save_prompt_lines(ed) -> tuple:
    """The save-as prompt's rows: title, the path being typed (a ``_`` cursor
    at its end; in ``[ ]`` when Ctrl+A selected all of it), the keys' hint."""
    text = f"[{ed.prompt}]  (selected: typing replaces it)" if ed.prompt_selected else ed.prompt + "_"
    return ("Save as (edit the path; Enter: save, Esc: cancel):", text,
            "Backspace deletes a character; Ctrl+A selects all; Ctrl+U or Ctrl+Backspace clears")


def error_box(ed, w: int, h: int, y: int) -> list:
    """The error box (a load / save error) at the top centre below ``y``,
    shown until dismissed; records its rectangle in ``ed.error_rect``."""
    if ed.error_box is None:
        ed.error_rect = None
        return []
    lines = error_lines(ed.error_box)
    img = ov.text_panel(tuple(lines), size=14, bg=(70, 18, 18, 240))
    img = img[:max(h, 1), :max(w, 1)]
    x = max((w - img.shape[1]) // 2, 0)
    y = min(max(y, PANEL_MARGIN), max(h - img.shape[0], 0))
    ed.error_rect = (x, y, img.shape[1], img.shape[0])
    return [ov.Patch(x, y, img)]


def compose_overlay(ed, w: int, h: int) -> list:
    """Every overlay patch of a frame, back to front: the tools' drawings,
    the panel (off the gizmo), progress bars, the help, a centred question."""
    patches = []
    s = ed.session
    if s is not None:
        patches += to_patches(ed.overlay_shapes(w, h), (w, h))   # the tools' shapes, painted on the CPU
    panel = ov.text_panel(tuple(panel_lines(ed))) if ed.panel_visible else None
    box = None
    if panel is not None:
        avoid = ed.gizmo.avoid_box(w, h) if s is not None else None
        box = place_panel((w, h), (panel.shape[1], panel.shape[0]), avoid)
    help_patch = ed.help.patch((w, h), box)
    if help_patch is not None and ed.help.covers_panel:
        panel = box = None             # too small a window for both: the help steps in front
    ed.panel_box = None if box is None else (box.x, box.y, box.w, box.h)
    y = PANEL_MARGIN
    if box is not None:
        patches.append(ov.Patch(box.x, box.y, panel))
        y = box.bottom + 6 if box.y == PANEL_MARGIN else PANEL_MARGIN
    x = box.x if box is not None else PANEL_MARGIN
    bars = [(j.stage, j.fraction) for j in ed.jobs.values()]
    if s is not None and s.fit_job is not None:
        bars.append((s.fit_job.stage, s.fit_job.fraction))
    c = None if s is None else s.committer.progress()
    if c is not None:
        bars.append((c.stage, c.fraction))
    for stage, frac in bars:
        bar = ov.progress_bar(360, frac, f"{stage} {frac * 100:3.0f}%")
        patches.append(ov.Patch(x, y, bar))
        y += bar.shape[0] + 4
    if help_patch is not None:
        patches.append(help_patch)
    patches += ed.browser.overlay(w, h)
    patches += error_box(ed, w, h, y)
    center_msg = restore_question(ed) or open_question(ed)
    if center_msg is not None:
        pass
    elif ed.confirm_quit:
        center_msg = ("Unsaved changes.", "Y / Q / Esc: quit without saving     N: keep editing",
                      "(Ctrl+S saves)")
    elif ed.prompt is not None:
        center_msg = save_prompt_lines(ed)
    if center_msg:
        img = ov.text_panel(center_msg, size=16, bg=(40, 20, 20, 235), min_width=420)
        patches.append(ov.Patch((w - img.shape[1]) // 2, (h - img.shape[0]) // 2, img))
    return patches

"""Box and lasso selection (Ctrl+B / Ctrl+Shift+B, or the Select menu): the
next left drag draws a rectangle or a free-hand loop; on release the
splats inside are added to the brush target (support or active handle),
or erased from it when Ctrl is held or the erase toggle (E) is on.  As the
brush's V mode says: *through* (3D mode) takes every splat whose centre
projects inside, hidden or not; *visible* takes only the splats seen inside.
The selection is then closed (:mod:`splatedit.select.closure`): one undo step.

A tool on the narrow protocol: it uses only :attr:`Tool.ctx`
(:class:`~splatedit.app.tools.base.ToolContext`) and draws through
:meth:`shapes`.
"""

from __future__ import annotations

import math

import numpy as np

from splatedit.app.ui.keymap import Action, Section
from splatedit.app.tools.shapes import Polyline
from splatedit.app.tools.base import DragMode, Tool

BOX, LASSO = "box", "lasso"
#: outline colours: adding / erasing
REGION_RGB = (255, 255, 255)
REGION_ERASE_RGB = (230, 60, 60)
#: a lasso point is kept when it is this many pixels from the last one
LASSO_STEP_PX = 2.0


def polygon_mask(poly: np.ndarray, w: int, h: int) -> np.ndarray:
    """(h, w) bool: the pixels whose centre lies inside the closed polygon
    ``poly`` ((m, 2) pixels, x right, y down; even-odd rule, so a lasso
    crossing itself leaves the doubly wound part out).  Scanline fill: one
    row at a time, the edges' crossings of the row's centre line sorted and
    filled pairwise; O(h m + area)."""
    p = np.asarray(poly, float).reshape(-1, 2)
    out = np.zeros((int(h), int(w)), bool)
    if len(p) < 3 or not np.isfinite(p).all():
        return out
    a, b = p, np.roll(p, -1, axis=0)
    y0 = max(int(math.floor(p[:, 1].min())), 0)
    y1 = min(int(math.ceil(p[:, 1].max())), h - 1)
    xc = np.arange(w) + 0.5
    for y in range(y0, y1 + 1):
        yc = y + 0.5
        cross = (a[:, 1] <= yc) != (b[:, 1] <= yc)       # the edge spans the line (half-open)
        if not cross.any():
            continue
        ea, eb = a[cross], b[cross]
        xs = np.sort(ea[:, 0] + (yc - ea[:, 1]) * (eb[:, 0] - ea[:, 0]) / (eb[:, 1] - ea[:, 1]))
        for x_in, x_out in zip(xs[0::2], xs[1::2]):
            out[y] |= (xc >= x_in) & (xc < x_out)
    return out


def box_polygon(p0, p1) -> np.ndarray:
    """(4, 2): the rectangle with opposite corners ``p0`` and ``p1``."""
    (x0, y0), (x1, y1) = p0, p1
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float)


def splats_through(mask: np.ndarray, px: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Sorted indices of the splats in front of the camera (``depth`` (n,)
    > 0) whose centre pixel ``px`` (n, 2) falls on ``mask`` (h, w)."""
    h, w = mask.shape
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(px).all(axis=1) & (depth > 0) & (px[:, 0] >= 0) & (px[:, 0] < w) \
            & (px[:, 1] >= 0) & (px[:, 1] < h)
    idx = np.flatnonzero(ok)
    inside = mask[px[idx, 1].astype(np.int64), px[idx, 0].astype(np.int64)]
    return idx[inside]


def splats_visible(mask: np.ndarray, picker) -> np.ndarray:
    """Sorted unique indices of the splats seen inside ``mask`` (h, w): those
    drawn front-most on a pixel of it (the pick map) and those whose visible
    centre falls on it (sub-pixel splats, :meth:`BrushPicker.visible_centres`)."""
    pick = picker.pick
    ids = pick[mask & (pick >= 0)]
    vis = picker.visible_centres()
    if len(vis) and picker.centers_px is not None:
        h, w = mask.shape
        px = picker.centers_px[vis]
        ix = np.clip(px[:, 0].astype(np.int64), 0, w - 1)
        iy = np.clip(px[:, 1].astype(np.int64), 0, h - 1)
        ids = np.concatenate([ids, vis[mask[iy, ix]]])
    return np.unique(ids.astype(np.int64))


class RegionSelectTool(Tool):
    """Box / lasso selection on the brush target (see the module docstring)."""
    section = Section.SELECTION
    #: the editor attribute it is reachable as (``editor.region``)
    name = "region"

    def __init__(self, ed):
        super().__init__(ed)
        self.armed: str | None = None      # BOX / LASSO: the next left drag draws it
        self.points: list[tuple[float, float]] = []
        self.erase = False

    def actions(self):
        return {Action.BOX_SELECT: lambda: self.arm(BOX), Action.LASSO_SELECT: lambda: self.arm(LASSO)}

    def arm(self, kind: str) -> None:
        """Arm ``kind`` (the same key again disarms it)."""
        if self.armed == kind:
            self.armed = None
            self.ctx.say(f"{kind} select cancelled")
            return
        self.armed = kind
        how = "drag a rectangle" if kind == BOX else "draw a loop"
        mode = "every splat inside, through" if self.ctx.through else "visible splats only (V: through)"
        self.ctx.say(f"{kind} select: {how} ({mode}; Ctrl: erase; right click: cancel)")

    def intercept(self, action):
        """Esc while a box or lasso is armed cancels it."""
        if action is Action.CANCEL and self.armed is not None:
            self.ctx.say(f"{self.armed} select cancelled")
            self.armed, self.points = None, []
            self.ctx.redraw()
            return True
        return False

    # ---------------------------------------------------------------- mouse
    def press_modal(self, e):
        if self.armed is None:
            return None
        g = self.ctx.keys
        if e.button == g.MOUSE_BUTTON_RIGHT:
            self.ctx.say(f"{self.armed} select cancelled")
            self.armed = None
            return DragMode.NONE
        if e.button != g.MOUSE_BUTTON_LEFT or (e.mods & g.MOD_ALT) or self.ctx.busy():
            return None                          # (Alt + left drag orbits, as without the box)
        self.points = [(float(e.x), float(e.y))]
        self.erase = self.ctx.erasing(e.mods)
        return DragMode.REGION

    def drag(self, mode, x, y, dx, dy, last):
        if mode is not DragMode.REGION:
            return
        if self.armed == BOX:
            self.points = [self.points[0], (float(x), float(y))]
        else:
            lx, ly = self.points[-1]
            if math.hypot(x - lx, y - ly) >= LASSO_STEP_PX:
                self.points.append((float(x), float(y)))
        self.ctx.redraw()

    def release(self, mode):
        if mode is not DragMode.REGION:
            return
        kind, pts = self.armed, self.points
        self.armed, self.points = None, []
        self.ctx.redraw()
        if kind is None or len(pts) < 2:
            return
        self.select_polygon(self.polygon(kind, pts), self.erase, kind)

    @staticmethod
    def polygon(kind: str, pts) -> np.ndarray:
        return box_polygon(pts[0], pts[-1]) if kind == BOX else np.asarray(pts, float)

    # ------------------------------------------------------------ selecting
    def region_splats(self, poly: np.ndarray) -> np.ndarray:
        """Sorted indices of the splats in the window polygon ``poly`` (m, 2)
        as the brush mode says (through / visible only)."""
        c = self.ctx
        w, h = c.size
        mask = polygon_mask(poly, w, h)
        if c.through:
            px, depth = c.camera.project(c.document.cloud.positions, w, h)
            return splats_through(mask, px, depth)
        return splats_visible(mask, c.visible())

    def select_polygon(self, poly: np.ndarray, erase: bool = False, kind: str = "region") -> bool:
        """Add the splats in ``poly`` to the brush target (``erase``: remove
        them), close the selection: one undo step.  True when it changed."""
        c = self.ctx
        if c.busy():
            return False
        idx = self.region_splats(poly)
        mask = c.target_mask().copy()
        mask[idx] = not erase
        what = c.target
        before = int(c.target_mask().sum())
        if not c.select(mask, f"{kind} {'erase' if erase else 'select'} {what}"):
            c.say(f"{kind} select: the {what} did not change ({len(idx):,} {c.items} inside)")
            return False
        c.say(f"{kind} {'erase' if erase else 'select'}: {what} {int(c.target_mask().sum()) - before:+,} {c.items}")
        return True

    def status(self):
        if self.armed is None:
            return None
        return f"{self.armed} select: left drag ({'through' if self.ctx.through else 'visible only'}; Esc cancels)"

    # -------------------------------------------------------------- drawing
    def shapes(self, w, h):
        if self.armed is None or len(self.points) < 2:
            return []
        rgb = REGION_ERASE_RGB if self.erase else REGION_RGB
        return [Polyline(self.polygon(self.armed, self.points), rgb, 2.0, closed=True)]


TOOL = RegionSelectTool

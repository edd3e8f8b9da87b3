"""Pivot and axes of G / R / S and the gizmo (as Blender's pivot and
orientation menus).

Pivot ("." cycles; the Pivot menu): the centre rotations and scalings turn
about, where the gizmo is drawn.

* *handle centre*: the active handle's posed centroid (the default);
* *support rim*: the centroid of the support's fixed rim, the support
  splats next to a splat outside the support (where a limb joins the
  body: an arm turns at its shoulder);
* *3D cursor*: a point placed on the surface under the mouse with
  Shift + right click (drawn as a ringed cross);
* *view centre*: the point the camera orbits.

Axes ("," cycles; the Pivot menu): the X / Y / Z of the gizmo's arrows
and rings and of the axis keys during a move: *global* (the model's axes),
*local* (the active handle's principal axes, longest first, turned by its
pending move) or *view* (screen right, screen up, towards the viewer).

A tool on the narrow protocol (:attr:`Tool.ctx`, :meth:`shapes`); the
gizmo asks :meth:`PivotTool.point` and :meth:`PivotTool.frame`.
"""

from __future__ import annotations

import math

import numpy as np

from splatedit.app.ui.keymap import Action, Section
from splatedit.app.tools.shapes import Polyline
from splatedit.app.tools.base import DragMode, Tool

HANDLE_CENTRE, SUPPORT_RIM, CURSOR, VIEW_CENTRE = "handle centre", "support rim", "3D cursor", "view centre"
PIVOTS = (HANDLE_CENTRE, SUPPORT_RIM, CURSOR, VIEW_CENTRE)
GLOBAL, LOCAL, VIEW = "global", "local", "view"
FRAMES = (GLOBAL, LOCAL, VIEW)
CURSOR_RGB = (235, 70, 70)
#: the 3D cursor's ring radius (pixels) and the surface search radius of its click
CURSOR_RING_PX = 9.0
CURSOR_PICK_PX = 8.0


def rim_centroid(positions: np.ndarray, support: np.ndarray, graph) -> np.ndarray | None:
    """(3,) centroid of the support splats with a neighbour-graph neighbour
    outside the support (``support`` (n,) bool), or None when there is none
    (the support is the whole model or a whole connected piece)."""
    sup = np.asarray(support, bool)
    if not sup.any() or sup.all():
        return None
    rim = graph.grow(~sup, 1) & sup
    if not rim.any():
        return None
    return np.asarray(positions, float)[rim].mean(axis=0)


def principal_frame(points: np.ndarray) -> np.ndarray:
    """(3, 3) right-handed orthonormal frame of ``points`` (m, 3): columns
    the principal axes, largest spread first (the world axes for fewer than
    3 points); the sign of each axis points towards the world axis it is
    closest to, so a frame does not flip between calls."""
    p = np.asarray(points, float).reshape(-1, 3)
    if len(p) < 3:
        return np.eye(3)
    q = p - p.mean(axis=0)
    _, vecs = np.linalg.eigh(q.T @ q)
    f = vecs[:, ::-1].copy()
    for k in range(2):
        j = int(np.argmax(np.abs(f[:, k])))
        if f[j, k] < 0:
            f[:, k] = -f[:, k]
    f[:, 2] = np.cross(f[:, 0], f[:, 1])
    return f


def orthonormal(m: np.ndarray) -> np.ndarray:
    """The rotation nearest to (3, 3) ``m`` (polar decomposition by SVD)."""
    u, _, vt = np.linalg.svd(np.asarray(m, float))
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] = -u[:, -1]
        r = u @ vt
    return r


class PivotTool(Tool):
    section = Section.DEFORMATION
    #: the editor attribute it is reachable as (``editor.pivot``)
    name = "pivot"

    def __init__(self, ed):
        super().__init__(ed)
        self.mode = HANDLE_CENTRE
        self.orientation = GLOBAL
        self.cursor: np.ndarray | None = None     # (3,) the 3D cursor, model units
        self._rim = (None, None)                   # (key, centroid)
        self._local = (None, None)                 # (key, the handle's principal frame)

    def actions(self):
        t = {Action.PIVOT_NEXT: self.next_mode, Action.AXES_NEXT: self.next_orientation,
             Action.CURSOR_TO_VIEW_CENTRE: self.cursor_to_view_centre}
        for a, m in zip((Action.PIVOT_HANDLE, Action.PIVOT_RIM, Action.PIVOT_CURSOR, Action.PIVOT_VIEW), PIVOTS):
            t[a] = lambda m=m: self.set_mode(m)
        for a, f in zip((Action.AXES_GLOBAL, Action.AXES_LOCAL, Action.AXES_VIEW), FRAMES):
            t[a] = lambda f=f: self.set_orientation(f)
        return t

    # -------------------------------------------------------------- settings
    def set_mode(self, mode: str) -> None:
        self.mode = mode
        note = ""
        if mode == CURSOR and self.cursor is None:
            note = ": place it with Shift + right click on the model (until then: the handle centre)"
        self.ctx.say(f"pivot: {mode}{note}")
        self.ctx.redraw()

    def next_mode(self) -> None:
        self.set_mode(PIVOTS[(PIVOTS.index(self.mode) + 1) % len(PIVOTS)])

    def set_orientation(self, name: str) -> None:
        self.orientation = name
        self.ctx.say(f"axes: {name}")
        self.ctx.redraw()

    def next_orientation(self) -> None:
        self.set_orientation(FRAMES[(FRAMES.index(self.orientation) + 1) % len(FRAMES)])

    def cursor_to_view_centre(self) -> None:
        self.cursor = np.asarray(self.ctx.camera.target, float).copy()
        self.ctx.say("3D cursor at the view centre")
        self.ctx.redraw()

    def place_cursor(self, x: float, y: float) -> bool:
        """Put the 3D cursor on the front surface under pixel (x, y); False
        over the background."""
        from splatedit.app.document.selection import surface_under
        c = self.ctx
        p = c.visible()
        hit = surface_under(p.pick, p.pick_depth, p.depths, x, y, CURSOR_PICK_PX)
        if hit is None:
            c.say("3D cursor: click on the model")
            return False
        w, h = c.size
        self.cursor = np.asarray(c.camera.point_at_depth(x, y, w, h, hit[1]), float)
        c.say("3D cursor placed" + ("" if self.mode == CURSOR else " (\".\" or the Pivot menu makes it the pivot)"))
        c.redraw()
        return True

    def status(self):
        if self.mode == HANDLE_CENTRE and self.orientation == GLOBAL:
            return None
        return f"pivot: {self.mode}   axes: {self.orientation}   (. ,)"

    # ------------------------------------------------------------ geometry
    def point(self) -> np.ndarray | None:
        """(3,) the pivot in model units, or None for the handle's centre
        (also where the chosen pivot does not exist: no cursor placed, no rim)."""
        c = self.ctx
        if self.mode == CURSOR:
            return self.cursor
        if self.mode == VIEW_CENTRE:
            return np.asarray(c.camera.target, float).copy()
        if self.mode == SUPPORT_RIM:
            doc = c.document
            from splatedit.app.document import revision
            key = (revision.of(doc.cloud), doc.selection.key()[1])
            if self._rim[0] != key:
                g = c.neighbour_graph()
                if g is None:
                    return None
                self._rim = (key, rim_centroid(doc.cloud.positions, doc.selection.support, g))
            return self._rim[1]
        return None

    def frame(self) -> np.ndarray:
        """(3, 3) the constraint axes (columns X, Y, Z) of the chosen orientation."""
        c = self.ctx
        if self.orientation == VIEW:
            r, u, b = c.camera.basis()
            return np.column_stack([r, u, b]).astype(float)
        if self.orientation == LOCAL:
            doc = c.document
            sel = doc.selection
            if not sel.handle.any():
                return np.eye(3)
            k = sel.active
            from splatedit.app.document import revision
            key = (revision.of(doc.cloud), doc.version, k)
            if self._local[0] != key:       # the handle's principal axes, once per document change
                self._local = (key, principal_frame(doc.cloud.positions[sel.handle]))
            pose = doc.pose[k] if k < len(doc.pose) else np.eye(4)
            return orthonormal(pose[:3, :3]) @ self._local[1]
        return np.eye(3)

    def frame_name(self) -> str:
        """The orientation's name in readouts ("" for the global axes)."""
        return "" if self.orientation == GLOBAL else self.orientation

    # ---------------------------------------------------------------- mouse
    def press_modal(self, e):
        g = self.ctx.keys
        if e.button == g.MOUSE_BUTTON_RIGHT and (e.mods & g.MOD_SHIFT) and not self.ctx.busy():
            self.place_cursor(e.x, e.y)
            return DragMode.NONE
        return None

    # -------------------------------------------------------------- drawing
    def shapes(self, w, h):
        if self.cursor is None:
            return []
        px, d = self.ctx.camera.project(self.cursor, w, h)
        if d[0] <= 0:
            return []
        x, y = float(px[0, 0]), float(px[0, 1])
        t = np.linspace(0.0, 2.0 * math.pi, 25)[:-1]
        r = CURSOR_RING_PX
        ring = np.column_stack([x + r * np.cos(t), y + r * np.sin(t)])
        rgb = CURSOR_RGB if self.mode == CURSOR else (200, 200, 200)
        return [Polyline(ring, rgb, 2.0, closed=True),
                Polyline(np.array([[x - 2 * r, y], [x + 2 * r, y]]), rgb, 1.0),
                Polyline(np.array([[x, y - 2 * r], [x, y + 2 * r]]), rgb, 1.0)]


TOOL = PivotTool

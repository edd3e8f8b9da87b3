"""Handle tool: the gizmo of the active handle (arrows: grab along an axis,
rings: rotate about an axis, the outer circle: scale), picking a handle by
clicking it, the G/R/S manipulations (mouse, axis keys, typed values) with
their live readout, and applying / discarding the pose."""

from __future__ import annotations

import math

import numpy as np

from splatedit.app.ui import overlay as ov
from splatedit.app.document import revision
from splatedit.app.ui.keymap import Action, Section, typed_char
from splatedit.app.document.session import GRAB, ROTATE, SCALE, ViewInfo
from splatedit.app.tools.shapes import TOP, Circle, Cross, Dot, Label, Polyline, place_inside
from splatedit.app.tools.base import DragMode, Tool
from splatedit.errors import SplatEditError
from splatedit.tolerances import (EDITOR_GIZMO_HIT_PX, EDITOR_GIZMO_MIN_PX, EDITOR_GIZMO_PX,
                                  EDITOR_GIZMO_RING_MIN_COS, EDITOR_GIZMO_RING_PX, EDITOR_GIZMO_RING_SEGMENTS,
                                  EDITOR_GIZMO_SCALE_PX, EDITOR_READOUT_MARGIN_PX, EDITOR_READOUT_OFFSET_PX)

READOUT_RGB = (255, 230, 120)


def readout_box(mouse, box_w: float, box_h: float, w: int, h: int) -> tuple[float, float]:
    """Top-left (x, y) pixels of the live readout's box (``box_w`` x
    ``box_h`` pixels, its padding included) in a ``w`` x ``h`` window:
    EDITOR_READOUT_OFFSET_PX right of and below the cursor ``mouse``, moved
    so that the whole box keeps EDITOR_READOUT_MARGIN_PX from every window
    edge (a box wider than the window starts at the left margin)."""
    off = EDITOR_READOUT_OFFSET_PX
    return place_inside(float(mouse[0]) + off, float(mouse[1]) + off, box_w, box_h, w, h, EDITOR_READOUT_MARGIN_PX)


class GizmoTool(Tool):
    section = Section.DEFORMATION

    def __init__(self, ed):
        super().__init__(ed)
        self._centre = None
        self._centre_key = None

    def actions(self):
        return {Action.GRAB: lambda: self.begin_key(GRAB), Action.ROTATE: lambda: self.begin_key(ROTATE),
                Action.SCALE: lambda: self.begin_key(SCALE), Action.COMMIT_POSE: self.commit_pose,
                Action.CANCEL: self.cancel_idle}

    def manip_actions(self):
        """Actions while a manipulation runs (Context.MANIP)."""
        def mode(m):
            self.ctx.document.manip.mode = m
            self.ctx.document.manip.typed = ""
        return {Action.GRAB: lambda: mode(GRAB), Action.ROTATE: lambda: mode(ROTATE),
                Action.SCALE: lambda: mode(SCALE),
                Action.AXIS_X: lambda: self.ctx.document.manip.set_axis(0),
                Action.AXIS_Y: lambda: self.ctx.document.manip.set_axis(1),
                Action.AXIS_Z: lambda: self.ctx.document.manip.set_axis(2),
                Action.TYPE_BACKSPACE: lambda: self.ctx.document.manip.backspace(),
                Action.MANIP_DONE: self.finish_manip, Action.MANIP_CANCEL: self.cancel_manip}

    def type_key(self, key: int) -> None:
        ch = typed_char(key)
        if ch is not None:
            self.ctx.document.manip.type_char(ch)

    # ------------------------------------------------------------ geometry
    def handle_centre(self) -> np.ndarray | None:
        """Posed centroid of the active handle (cached per document version,
        cloud revision and pose)."""
        s = self.ctx.document
        k = s.selection.active
        key = (s.version, revision.of(s.cloud), k, s.pose[k].tobytes() if k < len(s.pose) else b"")
        if self._centre_key != key:
            self._centre = s.handle_centroid() if s.selection.handle.any() else None
            self._centre_key = key
        return self._centre

    def pivot_point(self) -> np.ndarray | None:
        """The gizmo's centre: the chosen pivot (:mod:`splatedit.app.tools.pivot`),
        else the active handle's posed centroid (None without a handle)."""
        p = self.ctx.tool("pivot").point()
        return p if p is not None else self.handle_centre()

    def frame(self) -> np.ndarray:
        """(3, 3) the gizmo's axes (columns X, Y, Z), :meth:`PivotTool.frame`."""
        return self.ctx.tool("pivot").frame()

    def _begin(self, mode: str, mouse) -> bool:
        """Start ``mode`` about the chosen pivot with the chosen axes."""
        pv = self.ctx.tool("pivot")
        piv = pv.point()
        return self.ctx.document.begin(mode, self.view_info(piv), mouse, pivot=piv, frame=pv.frame(),
                                  frame_name=pv.frame_name())

    def view_info(self, pivot=None) -> ViewInfo:
        c = self.ctx
        w, h = c.size
        r, u, b = c.camera.basis()
        piv = c.document.handle_centroid() if pivot is None else np.asarray(pivot, float)
        px, depth = c.camera.project(piv, w, h)
        return ViewInfo(r, u, b, (float(px[0, 0]), float(px[0, 1])),
                        c.camera.world_per_pixel(max(float(depth[0]), 1e-9), h))

    def _base(self, w: int, h: int):
        """``(pivot, pivot_px, world_per_px)`` of the gizmo, or None when it is
        hidden (no fitted active handle, a manipulation running, the curve
        tool on, or the handle behind the eye / far off-screen)."""
        s = self.ctx.document
        if not s.active_fitted() or s.manip is not None or s.curve_mode:
            return None
        if self.handle_centre() is None:
            return None
        piv = self.pivot_point()
        cam = self.ctx.camera
        px, d = cam.project(piv, w, h)
        if d[0] <= 0:
            return None
        margin = EDITOR_GIZMO_SCALE_PX
        x, y = float(px[0][0]), float(px[0][1])
        if not (-margin <= x <= w + margin and -margin <= y <= h + margin):
            return None   # far off-screen: its rings would be huge patches for nothing
        return piv, px[0], cam.world_per_pixel(float(d[0]), h)

    def axes(self, w: int, h: int) -> list:
        """Screen segments ``(axis, p0, p1)`` of the translate arrows."""
        base = self._base(w, h)
        if base is None:
            return []
        piv, p0, wpp = base
        ends, de = self.ctx.camera.project(piv + self.frame().T * (wpp * EDITOR_GIZMO_PX), w, h)
        return [(k, p0, ends[k]) for k in range(3)
                if de[k] > 0 and float(np.hypot(*(ends[k] - p0))) > EDITOR_GIZMO_MIN_PX]

    def rings(self, w: int, h: int) -> list:
        """Screen polylines ``(axis, pixels (m, 2))`` of the rotate rings: a
        circle around the pivot in the plane normal to each of the chosen
        axes (closed; NaN behind the eye); rings seen almost edge-on are left out."""
        base = self._base(w, h)
        if base is None:
            return []
        piv, _, wpp = base
        back = self.ctx.camera.basis()[2]
        t = np.linspace(0.0, 2.0 * math.pi, EDITOR_GIZMO_RING_SEGMENTS + 1)
        t[-1] = 0.0
        out = []
        f = self.frame()
        for k in range(3):
            if abs(float(back @ f[:, k])) < EDITOR_GIZMO_RING_MIN_COS:
                continue
            u, v = f[:, (k + 1) % 3], f[:, (k + 2) % 3]
            pts = piv + wpp * EDITOR_GIZMO_RING_PX * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * v)
            px, d = self.ctx.camera.project(pts, w, h)
            px = np.array(px, float)
            px[np.asarray(d) <= 0] = np.nan
            out.append((k, px))
        return out

    def scale_circle(self, w: int, h: int):
        """``(centre_px, radius_px)`` of the uniform scale grip, or None."""
        base = self._base(w, h)
        return None if base is None else (base[1], float(EDITOR_GIZMO_SCALE_PX))

    def box(self, w: int, h: int) -> tuple[float, float, float, float] | None:
        """Screen bounding box ``(x0, y0, x1, y1)`` of the whole gizmo, or None."""
        base = self._base(w, h)
        if base is None:
            return None
        c = base[1]
        r = float(max(EDITOR_GIZMO_SCALE_PX, EDITOR_GIZMO_RING_PX, EDITOR_GIZMO_PX)) + 4
        return float(c[0]) - r, float(c[1]) - r, float(c[0]) + r, float(c[1]) + r

    def avoid_box(self, w: int, h: int) -> tuple[float, float, float, float] | None:
        """What the panel must not cover: the gizmo, or while a handle is being
        moved (gizmo hidden) the moved handle's centre and its surroundings."""
        box = self.box(w, h)
        s = self.ctx.document
        if box is not None or s.manip is None or not s.selection.handle.any():
            return box
        piv = self.handle_centre()
        m = s.current_matrix()
        px, d = self.ctx.camera.project(m[:3, :3] @ piv + m[:3, 3], w, h)
        if d[0] <= 0:
            return None
        r = float(EDITOR_GIZMO_PX)
        return float(px[0, 0]) - r, float(px[0, 1]) - r, float(px[0, 0]) + r, float(px[0, 1]) + r

    # ---------------------------------------------------------- hit tests
    def arrow_hit(self, x: float, y: float) -> int | None:
        """The arrow under pixel (x, y) (outer three quarters, EDITOR_GIZMO_HIT_PX)."""
        w, h = self.ctx.size
        best, axis = EDITOR_GIZMO_HIT_PX, None
        q = np.array([x, y])
        for k, p0, p1 in self.axes(w, h):
            d = p1 - p0
            t = float(np.clip((q - p0) @ d / (d @ d), 0.0, 1.0))
            dist = float(np.linalg.norm(q - (p0 + t * d)))
            if t >= 0.25 and dist <= best:
                best, axis = dist, k
        return axis

    def ring_hit(self, x: float, y: float) -> int | None:
        """The nearest rotate ring within EDITOR_GIZMO_HIT_PX of pixel (x, y)."""
        w, h = self.ctx.size
        best, axis = EDITOR_GIZMO_HIT_PX, None
        q = np.array([x, y], float)
        for k, px in self.rings(w, h):
            a, b = px[:-1], px[1:]
            ok = np.isfinite(a).all(axis=1) & np.isfinite(b).all(axis=1)
            if not ok.any():
                continue
            a, b = a[ok], b[ok]
            d = b - a
            dd = np.maximum((d * d).sum(axis=1), 1e-12)
            t = np.clip(((q - a) * d).sum(axis=1) / dd, 0.0, 1.0)
            dist = float(np.hypot(*(q - (a + t[:, None] * d)).T).min())
            if dist <= best:
                best, axis = dist, k
        return axis

    def scale_hit(self, x: float, y: float) -> bool:
        w, h = self.ctx.size
        c = self.scale_circle(w, h)
        return c is not None and abs(math.hypot(x - c[0][0], y - c[0][1]) - c[1]) <= EDITOR_GIZMO_HIT_PX

    def pick(self, x: float, y: float) -> tuple | None:
        """What a left press at (x, y) grabs: ``(GRAB, axis)`` on an arrow, else
        ``(ROTATE, axis)`` on a ring, else ``(SCALE, None)`` on the scale grip."""
        k = self.arrow_hit(x, y)
        if k is not None:
            return GRAB, k
        k = self.ring_hit(x, y)
        if k is not None:
            return ROTATE, k
        return (SCALE, None) if self.scale_hit(x, y) else None

    def ring_grab_point(self, k: int, w: int, h: int):
        """A pixel on ring ``k`` that :meth:`pick` maps to that ring (the ring
        point farthest from the arrows and the other rings; for the status
        file), or None when every point of it is covered by them."""
        rings = dict(self.rings(w, h))
        if k not in rings:
            return None
        q = rings[k][:-1]
        q = q[np.isfinite(q).all(axis=1)]
        if not len(q):
            return None
        ring_d = np.full(len(q), np.inf)
        for j, p in rings.items():
            p = p[np.isfinite(p).all(axis=1)]
            if j != k and len(p):
                ring_d = np.minimum(ring_d, np.hypot(q[:, None, 0] - p[None, :, 0],
                                                     q[:, None, 1] - p[None, :, 1]).min(axis=1))
        arrow_d = np.full(len(q), np.inf)
        for _, p0, p1 in self.axes(w, h):
            d = p1 - p0
            t = np.clip((q - p0) @ d / max(float(d @ d), 1e-12), 0.0, 1.0)
            arrow_d = np.minimum(arrow_d, np.hypot(*(q - (p0 + t[:, None] * d)).T))
        score = np.where(arrow_d > EDITOR_GIZMO_HIT_PX + 2, np.minimum(ring_d, arrow_d), -1.0)
        i = int(np.argmax(score))
        return q[i] if score[i] > 4.0 else None

    # --------------------------------------------------------------- mouse
    def press_modal(self, e):
        """While a manipulation runs: left click applies it, right click cancels."""
        s, g = self.ctx.document, self.ctx.keys
        if s.manip is None:
            return None
        if e.button == g.MOUSE_BUTTON_LEFT:
            self.finish_manip()
        elif e.button == g.MOUSE_BUTTON_RIGHT:
            s.cancel()
            self.ctx.redraw()
        return DragMode.NONE

    def press(self, e):
        c = self.ctx
        s, g = c.document, c.keys
        if e.button != g.MOUSE_BUTTON_LEFT or s.basis is None or (e.mods & g.MOD_CONTROL):
            return None
        x, y = e.x, e.y
        hit = self.pick(x, y)
        if hit is not None and self._begin(hit[0], (x, y)):
            if hit[1] is not None:
                s.manip.set_axis(hit[1])
            c.redraw()
            return DragMode.MANIP
        if c.tool("brush").erase_toggle:
            return None
        i = c.splat_under(x, y)
        k = s.selection.handle_of(i) if i >= 0 else -1
        c.debug(f"left press at {x:.0f},{y:.0f}: splat {i}, handle {k}")
        if k >= 0:
            s.select_handle(k)
            if self._begin(GRAB, (x, y)):
                c.redraw()
                return DragMode.MANIP
        return None

    def release(self, mode):
        if mode is DragMode.MANIP and self.ctx.document.manip is not None:
            self.finish_manip()

    # ------------------------------------------------------------- actions
    def begin_key(self, mode: str) -> None:
        """G / R / S: start moving the active handle with the mouse."""
        s, c = self.ctx.document, self.ctx
        if not s.active_fitted():
            c.say("paint a support region and a handle first" if not s.selection.handle.any()
                   else "the deformation is still being fitted" if s.fitting
                   else f"cannot move the handle: {s.fit_error}" if s.fit_error
                   else "the active handle is not fitted yet")
            return
        self._begin(mode, c.mouse)

    def cancel_manip(self) -> None:
        self.ctx.document.cancel()
        self.ctx.end_drag()

    def cancel_idle(self) -> None:
        """Esc with nothing moving: discard the pending moves, else leave the curve tool."""
        s = self.ctx.document
        if s.pose_pending:
            s.reset_pose()
            self.ctx.say("pending moves discarded")
        elif s.curve_mode:
            s.curve_mode = False

    def commit_pose(self) -> None:
        if self.ctx.document.pose_pending:
            self._apply(lambda s: s.commit())

    def finish_manip(self) -> None:
        """End the running move: applied at once for a single handle, else kept.
        A typed value that cannot be applied (a scale factor <= 0) is refused:
        the manipulation goes on."""
        self._apply(lambda s: s.finish() == "commit")

    def _apply(self, action) -> None:
        c, s = self.ctx, self.ctx.document
        c.end_drag()
        bad = s.manip.problem() if s.manip is not None else None
        if bad:
            c.say(f"{bad}: type another value (Backspace), or Esc to cancel")
            c.redraw()
            return
        try:
            if action(s):
                if s.committing:
                    c.say(f"applying edit {len(s.edits) + 1} in the background (the view stays live; "
                           "editing waits until it lands)")
                else:
                    c.say(f"edit {len(s.edits)} applied in {s.last_commit_seconds * 1e3:.0f} ms")
        except SplatEditError as exc:
            s.cancel()
            c.say(f"edit not applied: {exc}")
        c.redraw()

    def report_commit(self) -> None:
        """Show how a background commit ended (once): a message, or the
        error box when a splat degenerated (the document is unchanged)."""
        s, c = self.ctx.document, self.ctx
        out = s.commit_outcome
        if out is None:
            return
        s.commit_outcome = None
        if out.error is None:
            c.say(f"edit {out.edits} applied in {out.seconds:.1f} s")
        else:
            c.show_error(f"edit not applied: {out.error}")
        c.redraw()

    # ------------------------------------------------------------- drawing
    def shapes(self, w, h):
        """Inactive handles' crosses, the active handle's axes, rotation
        rings, scale circle, constraint axis, the pivot -> current line and
        the live readout next to the cursor (over the panels)."""
        c = self.ctx
        s, cam = c.document, c.camera
        out = []
        if len(s.selection.handles) > 1:        # inactive handles: a dark green cross at their centre
            for k, hm in enumerate(s.selection.handles):
                if k != s.selection.active and hm.any():
                    px, d = cam.project(s.handle_centroid(k), w, h)
                    if d[0] > 0:
                        out.append(Cross(px[0], (20, 90, 25), 6.0))
        out += self._handle_shapes(w, h)
        return out + self.readout_shapes()

    def _handle_shapes(self, w: int, h: int) -> list:
        c = self.ctx
        s, cam = c.document, c.camera
        if not s.selection.handle.any() or (s.manip_target and s.manip_target[0] == "curve"):
            return []
        out = []
        piv = self.handle_centre()
        m = s.current_matrix()
        cur = m[:3, :3] @ piv + m[:3, 3]
        grip = self.scale_circle(w, h)
        if grip is not None:
            out.append(Circle(grip[0], grip[1], (225, 225, 225), 1.0, halo=False))
        for k, px in self.rings(w, h):
            out.append(Polyline(px, ov.AXIS_RGB[k], 2.0, halo=False))
        for k, p0, p1 in self.axes(w, h):
            out += [Polyline(np.array([p0, p1]), ov.AXIS_RGB[k], 3.0, halo=False),
                    Dot(p1, ov.AXIS_RGB[k], 4.0, rim=False)]
        px, depth = cam.project(np.vstack([piv, cur]), w, h)
        if depth.min() <= 0:
            return out
        if s.manip is not None and s.manip.axis is not None:
            a = s.manip.axis_vector() * cam.scene_radius
            ends, d2 = cam.project(np.vstack([cur - a, cur + a]), w, h)
            if d2.min() > 0:
                out.append(Polyline(np.array(ends[:2]), ov.AXIS_RGB[s.manip.axis], 1.0, halo=False))
        if s.manip is not None:
            out.append(Polyline(np.array(px[:2]), (255, 255, 255), 1.0, halo=False))
        out.append(Cross(px[1], ov.HANDLE_RGB if s.active_fitted() else (200, 200, 200)))
        return out

    def readout_text(self) -> str | None:
        m = self.ctx.document.manip
        return None if m is None else m.readout()

    def readout_shapes(self) -> list:
        """The live distance / angle / factor, next to the cursor while moving."""
        text = self.readout_text()
        if text is None:
            return []
        mx, my = self.ctx.mouse
        off = EDITOR_READOUT_OFFSET_PX       # placed by the painter (its text size): readout_box's rule
        return [Label((mx + off, my + off), text, READOUT_RGB, size=13, keep_inside=True,
                      margin=EDITOR_READOUT_MARGIN_PX, name="readout", layer=TOP)]

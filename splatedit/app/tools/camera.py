"""Camera tool: orbit / pan / dolly drags, zoom to the cursor, framing and
the numpad views about the model's up axis."""

from __future__ import annotations

import math


from splatedit.app.document import revision
from splatedit.app.ui.keymap import Action, Section
from splatedit.app.tools.base import DragMode, Tool, free_area  # noqa: F401 (free_area: API)
from splatedit.app.view.coverage import coverage_estimate
from splatedit.app.view.coverage import hint as coverage_hint
from splatedit.io.formats import is_z_up
from splatedit.model.extent import FramingExtent, framing_extent
from splatedit.model.orientation import UpAxis, detect_cloud_up_axis, next_up


class CameraTool(Tool):
    section = Section.CAMERA

    def __init__(self, ed):
        super().__init__(ed)
        self.zoom_anchor = None          # (x, y, world point) kept while the cursor stays put
        self.up = UpAxis(1, 1)
        self._extent = None              # (cloud revision, FramingExtent)
        self._hint_key = None            # the view whose drawn coverage was last estimated

    @property
    def cam(self):
        return self.ctx.camera

    def actions(self):
        top = math.radians(89.0)
        return {Action.FRAME_ALL: self.frame_all, Action.FRAME_SELECTION: self.frame_selection,
                Action.VIEW_FRONT: lambda: self.view_preset(0.0, 0.0, "front"),
                Action.VIEW_RIGHT: lambda: self.view_preset(math.pi / 2, 0.0, "right"),
                Action.VIEW_TOP: lambda: self.view_preset(0.0, top, "top"),
                Action.VIEW_BACK: lambda: self.view_preset(math.pi, 0.0, "back"),
                Action.VIEW_LEFT: lambda: self.view_preset(-math.pi / 2, 0.0, "left"),
                Action.VIEW_BOTTOM: lambda: self.view_preset(0.0, -top, "bottom"),
                Action.CYCLE_UP_AXIS: self.cycle_up_axis}

    # ----------------------------------------------------------- up axis
    def detect_up(self, cloud, path) -> None:
        """Set the up axis from the model (and the file's format)."""
        self.set_up(detect_cloud_up_axis(cloud, path, z_up_format=is_z_up(path)))

    def fresh_view(self, cloud, path) -> None:
        """The view a newly opened model gets (as on the first open): its own
        up axis, the default front angle about it (yaw = pitch = 0), framed
        whole -- nothing of the previous model's view is kept."""
        self.zoom_anchor = None
        self.cam.yaw = self.cam.pitch = 0.0
        self.cam.screen_offset = (0.0, 0.0)
        self.detect_up(cloud, path)
        self.frame_all(say=False)             # the load message names far points

    def set_up(self, up: UpAxis) -> None:
        self.up = up
        self.cam.up_axis = up.vector
        self.ctx.redraw()

    def cycle_up_axis(self) -> None:
        self.set_up(next_up(self.up))
        self.view_preset(self.cam.yaw, self.cam.pitch)
        self.ctx.say(f"up axis {self.up.label} (numpad 1 / 3 / 7 views turn about it)")

    # ------------------------------------------------------------ framing
    def view_area(self) -> tuple[float, float, float, float]:
        """The part of the window framing fills (:meth:`ToolContext.view_area`)."""
        return self.ctx.view_area()

    def extent(self) -> FramingExtent | None:
        """The open model's :func:`~splatedit.model.extent.framing_extent`
        (its main body), computed once per cloud revision; None without a model."""
        s = self.ctx.document
        if s is None:
            return None
        key = revision.of(s.cloud)
        if self._extent is None or self._extent[0] != key:
            self._extent = (key, framing_extent(s.cloud.positions))
        return self._extent[1]

    def frame_all(self, say: bool = True) -> None:
        """Home: the model's main body (far outlier clumps left out, see
        :mod:`splatedit.model.extent`) fills the free part of the window;
        ``say``: tell on the status line when far points are left out."""
        ext = self.extent()
        if ext is None:
            return
        w, h = self.ctx.size
        self.cam.frame(ext.center, ext.radius, w / max(h, 1), area=self.view_area())
        self.ctx.redraw()
        if say:     # a view change replaces the previous status message with the view's name
            note = ext.note()
            self.ctx.say("view: the whole model" + (f"; left out of the view: {note}" if note else ""))

    def frame_selection(self) -> None:
        """F: the active handle (else the support) fills the free part of the window."""
        s = self.ctx.document
        if s is None:
            return
        m = s.selection.handle if s.selection.handle.any() else s.selection.support
        if not m.any():
            self.frame_all()
            return
        w, h = self.ctx.size
        self.cam.frame_points(s.cloud.positions[m], w / max(h, 1), area=self.view_area())
        self.ctx.redraw()
        self.ctx.say(f"view: the {'active handle' if s.selection.handle.any() else 'support'}")

    def view_preset(self, yaw: float, pitch: float, name: str | None = None) -> None:
        """A numpad view: turn about the pivot (the framed model stays where it
        is on screen); ``name`` ("front", "top", ...): the status line says it
        (replacing whatever the previous message was)."""
        self.cam.turn_to(yaw, pitch)
        self.ctx.redraw()
        if name is not None:
            self.ctx.say(f"view: {name} (about the up axis {self.up.label})")
            self._hint_key = None       # the view's name replaced any hint: estimate it again

    def _drawn_cloud(self):
        cloud = getattr(self.ctx.viewport, "cloud", None)
        return self.ctx.document.cloud if cloud is None else cloud

    def _view_key(self) -> tuple:
        vp = self.ctx.viewport
        return (self.cam.state(), tuple(self.ctx.size), revision.of(self._drawn_cloud()),
                float(vp.splat_scale), bool(getattr(vp, "two_sided", False)))

    def hint_checked(self) -> bool:
        """The current view's coverage was estimated (:meth:`view_hint` ran for it)."""
        return self.ctx.document is not None and self._hint_key == self._view_key()

    def view_hint(self) -> None:
        """A still view that draws (almost) nothing although many splats are
        in it (a raw scan's estimated normals seen edge-on or from behind,
        :mod:`splatedit.app.view.coverage`): say so on the status line, after
        the view's name when that is the message.  Estimated once per view."""
        c = self.ctx
        vp = c.viewport
        if c.document is None or getattr(vp, "gaussians", None) is not None:
            return
        key = self._view_key()
        if key == self._hint_key:
            return
        cloud = self._drawn_cloud()
        self._hint_key = key
        w, h = c.size
        culled = not getattr(vp, "two_sided", False)
        cov = coverage_estimate(cloud.positions, cloud.u, cloud.v, self.cam, w, h, self.view_area(),
                                float(vp.splat_scale), culling=culled)
        if cov.tiny:
            text = coverage_hint(cov, "Shift+1 / Shift+3 or a middle drag")
            if culled and cov.front < 0.5 * cov.in_view:
                text += ", or T: draw the splats seen from behind too"
            c.say(f"{c.message}; {text}" if c.message.startswith("view:") else text)

    # -------------------------------------------------------------- mouse
    def press(self, e):
        g = self.ctx.keys
        alt = bool(e.mods & g.MOD_ALT)
        if e.button == g.MOUSE_BUTTON_MIDDLE or (e.button == g.MOUSE_BUTTON_LEFT and alt):
            if e.mods & g.MOD_SHIFT:
                return DragMode.PAN
            return DragMode.DOLLY if (e.mods & g.MOD_CONTROL) and not alt else DragMode.ORBIT
        return None

    def drag(self, mode, x, y, dx, dy, last):
        if mode is DragMode.ORBIT:
            self.cam.orbit(dx, dy)
        elif mode is DragMode.PAN:
            self.cam.pan(dx, dy, self.ctx.size[1])
        elif mode is DragMode.DOLLY:
            self.cam.dolly(-dy / 20.0)
        else:
            return
        self.ctx.redraw()

    def scroll(self, e) -> None:
        """Wheel: zoom to the surface point under the cursor (picked once, when
        this view's pick map is at hand, then kept while the cursor stays put)."""
        c = self.ctx
        w, h = c.size
        anchor = self.zoom_anchor
        if anchor is None or abs(anchor[0] - e.x) > 2 or abs(anchor[1] - e.y) > 2:
            point = None
            if c.pick_ready() and not c.dragging():
                i = c.splat_under(e.x, e.y)
                if i >= 0:
                    point = c.document.cloud.positions[i].copy()
            if point is None:
                point = self.cam.point_at_depth(e.x, e.y, w, h, self.cam.distance)
            anchor = self.zoom_anchor = (e.x, e.y, point)
        _, d = self.cam.project(anchor[2], w, h)
        depth = float(d[0]) if d[0] > 0 else None
        self.cam.dolly(e.dy, e.x, e.y, w, h, depth)
        c.redraw()

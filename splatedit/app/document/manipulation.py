"""A G/R/S manipulation of a handle or a curve point: the matrix a mouse
drag or a typed value gives, and its live readout (no window, no GPU)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from splatedit.deform.transform import compose, rotate, scale, translate
from splatedit.tolerances import EDITOR_AXIS_MIN_SCREEN_LEN, EDITOR_MIN_SCALE_FACTOR

GRAB, ROTATE, SCALE = "grab", "rotate", "scale"
AXIS_NAMES = "XYZ"


def _axis_scaling(axis: np.ndarray, factor: float, center) -> np.ndarray:
    """Scale by ``factor`` (> 0) along the unit vector ``axis`` (3,) about ``center``."""
    a = np.asarray(axis, float)
    s = np.eye(4)
    s[:3, :3] += (factor - 1.0) * np.outer(a, a)
    c = np.asarray(center, float)
    return compose(translate(-c), s, translate(c))


# ------------------------------------------------------------ manipulation
@dataclass
class ViewInfo:
    """What a manipulation needs to know about the view when it starts."""
    right: np.ndarray
    up: np.ndarray
    back: np.ndarray
    pivot_px: tuple[float, float]
    world_per_px: float          # at the pivot's depth


@dataclass
class Manipulation:
    """A G/R/S transform of the handle being dragged or typed.

    Mouse: grab moves the pivot with the mouse in the view plane (projected on
    the constraint axis if any); rotate turns about the view axis (or the
    constraint axis) by the angle the mouse sweeps around the pivot's pixel;
    scale multiplies by the ratio of the mouse's distances to the pivot's
    pixel (along the constraint axis only, if any).  A typed number replaces
    the mouse value: grab distance in model units (along the axis, X when
    none), rotate degrees, scale factor.

    The X / Y / Z constraint axes are the columns of ``frame`` ((3, 3)
    orthonormal; None: the world axes), named ``frame_name`` in the readout
    and the history ("local", "view"; "" for the world axes).  ``pivot`` is
    the centre of rotate and scale (the handle's centre, the support's rim,
    the 3D cursor or the view centre: :mod:`splatedit.app.tools.pivot`).
    """
    mode: str
    pivot: np.ndarray
    view: ViewInfo
    start: tuple[float, float]
    mouse: tuple[float, float] = None
    axis: int | None = None
    typed: str = ""
    frame: np.ndarray | None = None
    frame_name: str = ""

    def __post_init__(self):
        if self.mouse is None:
            self.mouse = self.start

    def set_axis(self, axis: int) -> None:
        """X/Y/Z key: constrain to that axis; pressing it again removes it."""
        self.axis = None if self.axis == axis else axis

    def type_char(self, ch: str) -> bool:
        if ch in "0123456789.":
            self.typed += ch
        elif ch == "-":
            self.typed = self.typed[1:] if self.typed.startswith("-") else "-" + self.typed
        else:
            return False
        return True

    def backspace(self) -> None:
        self.typed = self.typed[:-1]

    def typed_value(self) -> float | None:
        t = self.typed
        if t in ("", "-", ".", "-."):
            return None
        try:
            return float(t)
        except ValueError:
            return None

    def problem(self) -> str | None:
        """Why the typed value cannot be applied (None when it can): a scale
        factor must be > 0 (a negative one mirrors the handle and turns its
        normals inside out, 0 flattens it)."""
        v = self.typed_value()
        if v is not None and not math.isfinite(v):
            return "the typed value is too large"
        if self.mode == SCALE and v is not None and not v > 0:
            return f"the scale factor must be > 0, got {self.typed}"
        return None

    def _axis_vec(self) -> np.ndarray:
        if self.frame is not None:
            a = np.asarray(self.frame, float)[:, self.axis]
            return a / np.linalg.norm(a)
        a = np.zeros(3)
        a[self.axis] = 1.0
        return a

    def axis_vector(self) -> np.ndarray | None:
        """(3,) unit vector of the constraint axis in the model, or None."""
        return None if self.axis is None else self._axis_vec()

    def axis_name(self) -> str:
        """``X``, ``local X``, ``view Z`` ... ("" without a constraint)."""
        if self.axis is None:
            return ""
        return (f"{self.frame_name} " if self.frame_name else "") + AXIS_NAMES[self.axis]

    def _translation(self, typed) -> np.ndarray:
        """(3,) grab displacement, model units."""
        v = self.view
        if typed is not None:
            if self.axis is not None:
                a = self._axis_vec()
            else:
                a = np.asarray(self.frame, float)[:, 0] if self.frame is not None else np.array([1.0, 0.0, 0.0])
            return a * typed
        dx = self.mouse[0] - self.start[0]
        dy = self.mouse[1] - self.start[1]
        if self.axis is None:
            return (v.right * dx - v.up * dy) * v.world_per_px
        a = self._axis_vec()
        # the mouse motion along the axis's screen direction
        sa = np.array([a @ v.right, -(a @ v.up)])
        L = float(np.hypot(*sa))
        if L < EDITOR_AXIS_MIN_SCREEN_LEN:
            return np.zeros(3)
        return a * ((dx * sa[0] + dy * sa[1]) / (L * L) * v.world_per_px)

    def _angle_deg(self, typed) -> float:
        """Rotation angle (degrees, right-handed about :meth:`_rot_axis`)."""
        if typed is not None:
            return float(typed)
        v = self.view
        cx, cy = v.pivot_px
        a0 = math.atan2(self.start[1] - cy, self.start[0] - cx)
        a1 = math.atan2(self.mouse[1] - cy, self.mouse[0] - cx)
        # y is down: a growing atan2 is a clockwise sweep on screen, which is a
        # negative (right-handed) rotation about the axis pointing at the viewer
        ang = -(a1 - a0)
        if float(self._rot_axis() @ v.back) < 0:
            ang = -ang
        ang = (ang + math.pi) % (2 * math.pi) - math.pi      # the same rotation, in (-180, 180]
        return math.degrees(ang)

    def _rot_axis(self) -> np.ndarray:
        return self._axis_vec() if self.axis is not None else self.view.back

    def _factor(self, typed) -> float:
        if typed is not None:
            f = typed
        else:
            cx, cy = self.view.pivot_px
            r0 = math.hypot(self.start[0] - cx, self.start[1] - cy)
            r1 = math.hypot(self.mouse[0] - cx, self.mouse[1] - cy)
            f = r1 / max(r0, 1.0)
        return max(f, EDITOR_MIN_SCALE_FACTOR)

    def _typed_ok(self):
        return self.typed_value() if self.problem() is None else None

    def matrix(self) -> np.ndarray:
        """The manipulation's (4, 4) matrix; a typed value that cannot be
        applied (:meth:`problem`, shown by :meth:`describe`) is ignored: the
        mouse's value is used meanwhile."""
        typed = self._typed_ok()
        if self.mode == GRAB:
            return translate(self._translation(typed))
        if self.mode == ROTATE:
            return rotate(self._rot_axis(), self._angle_deg(typed), self.pivot)
        if self.mode == SCALE:
            f = self._factor(typed)
            if self.axis is None:
                return scale(f, self.pivot)
            return _axis_scaling(self._axis_vec(), f, self.pivot)
        raise ValueError(self.mode)

    def readout(self) -> str:
        """The live value of the move, as the overlay shows it next to the
        cursor: grab distance (model units) and its X/Y/Z components, rotate
        angle (degrees), scale factor; "typed" when it comes from the keys."""
        typed = self._typed_ok()
        src = "  (typed)" if typed is not None else ""
        ax = f" {self.axis_name()}" if self.axis is not None else ""
        if self.mode == GRAB:
            d = self._translation(typed)
            return f"distance{ax} {format_number(self._distance(d), '.4g')}   ({', '.join(format_number(v) for v in d)}){src}"
        if self.mode == ROTATE:
            return f"angle{ax} {self._angle_deg(typed):+.1f} deg{src}"
        return f"factor{ax} {self._factor(typed):.3f}x{src}"

    def _distance(self, d: np.ndarray) -> float:
        """The grab's main figure: signed along the constraint axis, else the length."""
        return float(d @ self._axis_vec()) if self.axis is not None else float(np.linalg.norm(d))

    def label(self) -> str:
        """The move's name in the edit history: ``Grab 0.12``, ``Grab -0.05
        along X``, ``Rotate 45 deg about Z``, ``Scale x1.38``."""
        typed = self._typed_ok()
        axis = self.axis_name() or None
        if self.mode == GRAB:
            return f"Grab {format_number(self._distance(self._translation(typed)))}" + (f" along {axis}" if axis else "")
        if self.mode == ROTATE:
            return f"Rotate {format_number(self._angle_deg(typed), '.3g')} deg about {axis or 'the view axis'}"
        return f"Scale x{format_number(self._factor(typed))}" + (f" along {axis}" if axis else "")

    def describe(self) -> str:
        name = {GRAB: "Grab", ROTATE: "Rotate", SCALE: "Scale"}[self.mode]
        prep = "about" if self.mode == ROTATE else "along"
        ax = f" {prep} {self.axis_name()}" if self.axis is not None else ""
        val = f"  value: {self.typed}" if self.typed else ""
        bad = self.problem()
        if bad:
            val += f"  ({bad})"
        return f"{name}{ax}{val}   (Enter/click: apply, Esc/right click: cancel)"


def format_number(v: float, fmt: str = ".3g") -> str:
    """``v`` formatted with ``fmt``, never as "-0" (a component rounding to zero reads 0)."""
    text = format(float(v), fmt)
    return "0" if float(text) == 0 else text

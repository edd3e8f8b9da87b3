"""Numeric transform of what is active: a handle or a picked curve point
(the GUI's transform fields).

:func:`field_target` says what the fields act on (:class:`TransformTarget`):
the active picked point of the control curve while the curve tool is on (or
when there is no handle), else the active handle; with its current
position (the handle's posed centroid, the point's moved position) and why
it cannot be edited now (nothing painted or picked, the fit still running,
a move running).  :class:`TransformInput` holds the relative fields: a
translation (model units), a rotation (axis + degrees) and a uniform scale
factor, applied in that order *reversed* (scale, then rotate, both about
the target's position, then translate), so each field reads as a G / R / S
typed into the keyboard; a curve point only moves.  :func:`apply_transform`
and :func:`apply_position` (the absolute "position" field) run it through
the same path as a finished G/R/S move or a dragged curve dot
(:meth:`GizmoTool.finish_manip`: committed at once for a single handle,
kept as a pending pose otherwise; an undo step either way) by handing the
session a :class:`FixedManipulation` whose matrix is the typed one.
No window, no GPU.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

import numpy as np

from splatedit.app.document.manipulation import GRAB, Manipulation, ViewInfo
from splatedit.deform.transform import compose, rotate, scale, translate
from splatedit.errors import SplatEditError
from splatedit.tolerances import EDITOR_GUI_MIN_AXIS_NORM


@dataclass
class TransformInput:
    """The transform fields: ``translate`` (3,) model units, ``axis`` (3,)
    (any length > 0), ``degrees`` (right-handed about ``axis``), ``factor``
    (uniform scale, > 0)."""
    translate: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    axis: list = field(default_factory=lambda: [0.0, 1.0, 0.0])
    degrees: float = 0.0
    factor: float = 1.0

    def problem(self) -> str | None:
        """Why the fields cannot be applied (None when they can)."""
        vals = [*self.translate, *self.axis, self.degrees, self.factor]
        if not all(math.isfinite(float(v)) for v in vals):
            return "a field is not a finite number"
        if not self.factor > 0:
            return f"the scale factor must be > 0, got {self.factor:g}"
        if self.degrees != 0 and float(np.linalg.norm(self.axis)) < EDITOR_GUI_MIN_AXIS_NORM:
            return "the rotation axis is zero"
        return None

    def is_identity(self) -> bool:
        return not any(self.translate) and self.degrees == 0 and self.factor == 1.0

    def matrix(self, pivot) -> np.ndarray:
        """(4, 4): scale and rotate about ``pivot`` (3,), then translate."""
        p = np.asarray(pivot, float)
        parts = [scale(float(self.factor), p)]
        if self.degrees != 0:
            parts.append(rotate(np.asarray(self.axis, float), float(self.degrees), p))
        parts.append(translate(np.asarray(self.translate, float)))
        return compose(*parts)

    def reset(self) -> None:
        self.translate = [0.0, 0.0, 0.0]
        self.degrees = 0.0
        self.factor = 1.0

    def label(self) -> str:
        """The edit's name in the history: ``Move (0.05, 0, 0), Rotate 30 deg, Scale x1.2``."""
        from splatedit.app.document.manipulation import format_number
        parts = []
        if any(self.translate):
            parts.append(f"Move ({', '.join(format_number(v) for v in self.translate)})")
        if self.degrees != 0:
            parts.append(f"Rotate {format_number(self.degrees)} deg")
        if self.factor != 1.0:
            parts.append(f"Scale x{format_number(self.factor)}")
        return ", ".join(parts) or "Transform"

    def describe(self) -> str:
        t = self.translate
        return (f"move ({t[0]:+.4g}, {t[1]:+.4g}, {t[2]:+.4g})  rotate {self.degrees:+.4g} deg about "
                f"({self.axis[0]:.3g}, {self.axis[1]:.3g}, {self.axis[2]:.3g})  scale {self.factor:.4g}x")


class FixedManipulation(Manipulation):
    """A manipulation whose matrix was typed into the fields (not the mouse's)."""

    def __init__(self, fixed: np.ndarray, pivot, text: str, label: str = "Transform"):
        view = ViewInfo(np.eye(3)[0], np.eye(3)[1], np.eye(3)[2], (0.0, 0.0), 1.0)
        super().__init__(GRAB, np.asarray(pivot, float), view, (0.0, 0.0))
        self._fixed = np.array(fixed, float)
        self._text = text
        self._label = label

    def label(self) -> str:
        return self._label

    def matrix(self) -> np.ndarray:
        return self._fixed.copy()

    def problem(self) -> str | None:
        return None

    def readout(self) -> str:
        return self._text

    def describe(self) -> str:
        return f"typed transform: {self._text}"


class TargetKind(enum.Enum):
    """What the transform fields act on (values: the session's ``manip_target`` kinds)."""
    NONE = "none"
    HANDLE = "handle"
    CURVE_POINT = "curve"


@dataclass(frozen=True)
class TransformTarget:
    """What the fields act on: ``kind``, ``index`` (handle / picked point),
    ``position`` (3,) model units (the handle's posed centroid, the point's
    moved position; None for NONE), ``label`` (for the panel) and ``problem``
    (why it cannot be edited now; None when it can)."""
    kind: TargetKind
    index: int = -1
    position: np.ndarray | None = None
    label: str = ""
    problem: str | None = None

    @property
    def rotates(self) -> bool:
        """Rotate and scale apply (a handle; a curve point only moves)."""
        return self.kind is TargetKind.HANDLE


def field_target(s) -> TransformTarget:
    """The fields' target in session ``s`` (see the module docstring)."""
    if s is None:
        return TransformTarget(TargetKind.NONE, problem="no model open")
    j = s.active_curve_point()
    has_handle = bool(s.selection.handle.any())
    if j is not None and (s.curve_mode or not has_handle):
        label = f"curve point {j + 1} of {len(s.curve_points)}"
        bad = _busy(s)
        if bad is None and (s.basis is None or s.basis_groups[1] is None):
            bad = ("add a second curve point" if len(s.curve_points) < 2
                   else "the deformation is still being fitted" if s.fitting
                   else s.fit_error or "paint a support region first (1)")
        return TransformTarget(TargetKind.CURVE_POINT, j, s.curve_point_positions(live=False)[j], label, bad)
    if not has_handle:
        return TransformTarget(TargetKind.NONE, problem="paint a support region (1) and a handle (2), "
                               "or pick curve points (K), first")
    k = s.selection.active
    label = f"handle {k + 1}" + (f" of {len(s.selection.handles)}" if len(s.selection.handles) > 1 else "")
    bad = _busy(s)
    if bad is None and not s.active_fitted():
        bad = ("paint a support region first (1)" if not s.selection.support.any()
               else "the deformation is still being fitted" if s.fitting
               else s.fit_error or "the active handle is not fitted")
    return TransformTarget(TargetKind.HANDLE, k, s.handle_centroid(), label, bad)


def _busy(s) -> str | None:
    if s.committing:
        return "the last edit is still being applied: wait until it lands"
    if s.manip is not None:
        return "a move is running: finish it (Enter) or cancel it (Esc) first"
    return None


def apply_transform(ed, fields: TransformInput) -> bool:
    """Apply ``fields`` to the :func:`field_target` as a G/R/S move (or a
    dragged curve dot) would be applied; says why not (editor message) and
    returns False when it cannot."""
    s = ed.session
    if s is None:
        return False
    t = field_target(s)
    bad = fields.problem() or t.problem
    if bad is None and not t.rotates and (fields.degrees != 0 or fields.factor != 1.0):
        bad = "a curve point only moves: set degrees to 0 and scale to 1"
    if bad is None and fields.is_identity():
        bad = "nothing to apply (all fields are at their neutral values)"
    if bad is not None:
        ed.say(f"transform: {bad}")
        return False
    s.manip = FixedManipulation(fields.matrix(t.position), t.position, fields.describe(), fields.label())
    s.manip_target = (t.kind.value, t.index)
    ed.gizmo.finish_manip()
    return True


def apply_position(ed, position) -> bool:
    """Move the :func:`field_target` so its position becomes ``position``
    (3,) model units (the "position" field); False (and a message) when it
    cannot, or when it is already there."""
    s = ed.session
    t = field_target(s)
    try:
        p = np.array(position, dtype=np.float64).reshape(3)
    except (TypeError, ValueError) as exc:
        raise SplatEditError(f"transform: position must be 3 numbers ({exc})") from None
    if t.position is not None and t.problem is None and np.array_equal(p, t.position):
        ed.say("transform: already at that position")
        return False
    here = t.position if t.position is not None else p
    return apply_transform(ed, TransformInput(translate=[float(x) for x in p - here]))

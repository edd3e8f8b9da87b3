"""Numeric transform of the active handle (the GUI's transform fields).

:class:`TransformInput` holds what the fields show: a translation (model
units), a rotation (axis + degrees) and a uniform scale factor, applied in
that order *reversed* (scale, then rotate, both about the handle's posed
centroid, then translate), so each field reads as a G / R / S typed into the
keyboard.  :func:`apply_transform` runs it through the same path as a
finished G/R/S move (:meth:`GizmoTool.finish_manip`: committed at once for a
single handle, kept as a pending pose with several handles), by handing the
session a :class:`FixedManipulation` whose matrix is the typed one.
No window, no GPU.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from splatedit.app.manipulation import GRAB, Manipulation, ViewInfo
from splatedit.deform.transform import compose, rotate, scale, translate
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

    def describe(self) -> str:
        t = self.translate
        return (f"move ({t[0]:+.4g}, {t[1]:+.4g}, {t[2]:+.4g})  rotate {self.degrees:+.4g} deg about "
                f"({self.axis[0]:.3g}, {self.axis[1]:.3g}, {self.axis[2]:.3g})  scale {self.factor:.4g}x")


class FixedManipulation(Manipulation):
    """A manipulation whose matrix was typed into the fields (not the mouse's)."""

    def __init__(self, fixed: np.ndarray, pivot, text: str):
        view = ViewInfo(np.eye(3)[0], np.eye(3)[1], np.eye(3)[2], (0.0, 0.0), 1.0)
        super().__init__(GRAB, np.asarray(pivot, float), view, (0.0, 0.0))
        self._fixed = np.array(fixed, float)
        self._text = text

    def matrix(self) -> np.ndarray:
        return self._fixed.copy()

    def problem(self) -> str | None:
        return None

    def readout(self) -> str:
        return self._text

    def describe(self) -> str:
        return f"typed transform: {self._text}"


def apply_transform(ed, fields: TransformInput) -> bool:
    """Apply ``fields`` to the active handle as a G/R/S move would be applied;
    says why not (editor message) and returns False when it cannot."""
    s = ed.session
    if s is None:
        return False
    bad = fields.problem()
    if bad is None and s.manip is not None:
        bad = "a move is running: finish it (Enter) or cancel it (Esc) first"
    if bad is None and not s.active_fitted():
        bad = ("paint a support region and a handle first" if not s.selection.handle.any()
               else "the deformation is still being fitted" if s.fitting else "the active handle is not fitted")
    if bad is None and fields.is_identity():
        bad = "nothing to apply (all fields are at their neutral values)"
    if bad is not None:
        ed.say(f"transform: {bad}")
        return False
    pivot = s.handle_centroid()
    s.manip = FixedManipulation(fields.matrix(pivot), pivot, fields.describe())
    s.manip_target = ("handle", s.selection.active)
    ed.gizmo.finish_manip()
    return True

"""The panel's Transform section (Dear ImGui): the numeric fields of what
is active (:func:`splatedit.app.ui.transform_fields.field_target`: a handle or
a picked curve point).

Rows: what the fields act on; its absolute ``position`` (Enter moves it
there); the relative ``move`` / ``axis`` / ``degrees`` / ``scale`` fields
with Apply (Enter in a field applies too; rotate and scale only for a
handle); for a curve, buttons choosing the point.  Everything is shown
disabled, with the reason, while it cannot be applied (nothing painted or
picked, the fit running, a move running).  Each change is one undo step.
"""

from __future__ import annotations

import numpy as np
from imgui_bundle import imgui

from splatedit.app.document import revision

from splatedit.app.ui.transform_fields import (TargetKind, TransformInput, apply_position, apply_transform,
                                            field_target)

RED = imgui.ImVec4(1.0, 0.47, 0.47, 1.0)


#: the fields show positions and moves to this fraction of the model's
#: diagonal (1e-4: a 0.16 mm step on a 1.6 m model): "-0.0006" rather than
#: "-0.00060034", which the three fields of a 1280x720 panel cut off
FIELD_PRECISION_REL = 1e-4


def length_format(diagonal: float) -> str:
    """printf format of a length field for a model ``diagonal`` units across:
    as many decimals as FIELD_PRECISION_REL of the diagonal needs, at most 6."""
    step = max(float(diagonal), 1e-300) * FIELD_PRECISION_REL
    decimals = int(min(6, max(0, -np.floor(np.log10(step)))))
    return f"%.{decimals}f"


def _entered() -> bool:
    """The last input field was left with Enter this frame."""
    return imgui.is_item_deactivated() and (imgui.is_key_pressed(imgui.Key.enter)
                                            or imgui.is_key_pressed(imgui.Key.keypad_enter))


class TransformSection:
    """State of the section between frames: the relative fields and the
    position being typed (shown from the model whenever it is not)."""

    def __init__(self, ed):
        self.ed = ed
        self.fields = TransformInput()
        self.position: list = [0.0, 0.0, 0.0]
        self._typing = False
        self._fmt = None            # (cloud revision, length format)

    def _length_format(self, session) -> str:
        """:func:`length_format` of the open model, computed once per cloud revision."""
        if session is None:
            return "%.4g"
        key = revision.of(session.cloud)
        if self._fmt is None or self._fmt[0] != key:
            self._fmt = (key, length_format(session.cloud.diagonal))
        return self._fmt[1]

    def draw(self, rect) -> None:
        """Lay out the section; ``rect(name)`` records the last item's rectangle."""
        ed, f = self.ed, self.fields
        s = ed.session
        t = field_target(s)
        imgui.text(t.label if t.kind is not TargetKind.NONE else "nothing to transform")
        rect("transform_target")
        if t.problem:
            imgui.push_text_wrap_pos(0.0)
            imgui.text_disabled(t.problem)
            imgui.pop_text_wrap_pos()
        if t.kind is TargetKind.CURVE_POINT and len(s.curve_points) > 1:
            imgui.same_line()
            if imgui.small_button("<") and s.manip is None:
                s.select_curve_point(t.index - 1)
            rect("curve_point_prev")
            imgui.same_line()
            if imgui.small_button(">") and s.manip is None:
                s.select_curve_point(t.index + 1)
            rect("curve_point_next")
        imgui.begin_disabled(t.problem is not None)
        if not self._typing:
            self.position = [float(x) for x in t.position] if t.position is not None else [0.0, 0.0, 0.0]
        fmt = self._length_format(s)
        imgui.set_next_item_width(220)
        _, v = imgui.input_float3("position", self.position, fmt)
        self.position = list(v)
        moved = _entered()
        self._typing = imgui.is_item_active()
        rect("field_position")
        imgui.set_next_item_width(220)
        _, v = imgui.input_float3("move", f.translate, fmt)
        f.translate = list(v)
        go = _entered()
        rect("field_translate")
        imgui.begin_disabled(not t.rotates)
        imgui.set_next_item_width(220)
        _, v = imgui.input_float3("axis", f.axis, "%.3g")
        f.axis = list(v)
        go |= _entered()
        imgui.set_next_item_width(100)
        _, f.degrees = imgui.input_float("degrees", f.degrees, 0.0, 0.0, "%.4g")
        go |= _entered()
        rect("field_degrees")
        imgui.set_next_item_width(100)
        _, f.factor = imgui.input_float("scale", f.factor, 0.0, 0.0, "%.4g")
        go |= _entered()
        rect("field_scale")
        imgui.end_disabled()
        if imgui.button("Apply"):
            go = True
        rect("transform_apply")
        imgui.same_line()
        if imgui.button("Reset fields"):
            f.reset()
        imgui.end_disabled()
        bad = f.problem()
        if bad:
            imgui.text_colored(RED, bad)
        if moved and t.problem is None:
            self._typing = False
            apply_position(ed, np.array(self.position, float))
        elif go and apply_transform(ed, f):
            f.reset()

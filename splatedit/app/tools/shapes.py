"""Backend-neutral overlay shapes of the tool protocol.

A tool's :meth:`~splatedit.app.tools.base.Tool.shapes` returns a list of
these; one painter draws them: :func:`to_patches` for the CPU overlay
(:mod:`splatedit.app.ui.overlay` patches, composited on the frame) and
:func:`splatedit.app.ui.gui_overlay.draw_shapes` for the GPU path (ImGui draw
lists).  A tool written on the protocol so draws the same in both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Polyline:
    """A line strip through ``points`` ((m, 2) window pixels, x right, y
    down; NaN rows break it), ``rgb`` 0..255, ``width`` pixels; ``closed``
    joins the last point to the first."""
    points: np.ndarray
    rgb: tuple
    width: float = 2.0
    closed: bool = False

    def strip(self) -> np.ndarray:
        """(m', 2) float: the points, the first repeated at the end when closed."""
        p = np.asarray(self.points, float).reshape(-1, 2)
        return np.vstack([p, p[:1]]) if self.closed and len(p) > 1 else p


def to_patches(shapes) -> list:
    """The CPU overlay patches of ``shapes`` (unknown shapes are an error)."""
    from splatedit.app.ui import overlay as ov
    out = []
    for s in shapes:
        if not isinstance(s, Polyline):
            raise TypeError(f"not an overlay shape: {s!r}")
        p = ov.polyline_patch(s.strip(), s.rgb, width=max(int(round(s.width)), 1))
        if p is not None:
            out.append(p)
    return out

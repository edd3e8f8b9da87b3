"""The editor's tools: each owns its mouse input, its keymap actions, its
overlay drawing and its help entries (:class:`~splatedit.app.tools.base.Tool`).

* :class:`~splatedit.app.tools.camera.CameraTool`: orbit / pan / dolly / zoom,
  framing, numpad views about the up axis;
* :class:`~splatedit.app.tools.brush.BrushTool`: support / handle painting
  and the selection tools (grow, shrink, connected, invert, closure);
* :class:`~splatedit.app.tools.gizmo.GizmoTool`: the handle gizmo (arrows,
  rings, scale grip) and G/R/S manipulations with their live readout;
* :class:`~splatedit.app.tools.curve.CurveTool`: the control curve.

Every tool is on the narrow protocol (:attr:`~splatedit.app.tools.base.Tool.ctx`,
:meth:`~splatedit.app.tools.base.Tool.shapes`,
:meth:`~splatedit.app.tools.base.Tool.status`); the four above are made by
the editor itself (they come first in press order), the others register themselves: a module
of this package that sets ``TOOL = SomeTool`` is found by
:func:`protocol_tools`, and the editor makes one, reachable as
``editor.<SomeTool.name>``.  A new tool is that file plus its keymap rows
(:mod:`splatedit.app.ui.keymap`):

* :class:`~splatedit.app.tools.region.RegionSelectTool`: box and lasso selection;
* :class:`~splatedit.app.tools.mirror.MirrorTool`: mirror selection, symmetric painting;
* :class:`~splatedit.app.tools.delete.DeleteTool`: delete / crop the selected splats;
* :class:`~splatedit.app.tools.pivot.PivotTool`: the pivot and the axes of G / R / S.
"""

from __future__ import annotations


def protocol_tools() -> list[type]:
    """The tool classes of this package's modules that set ``TOOL``, by
    their ``order`` then name (the order mouse presses are offered in, after
    the built-in tools' ``press_modal``)."""
    import importlib
    import pkgutil
    found = []
    for m in pkgutil.iter_modules(__path__):
        cls = getattr(importlib.import_module(f"{__name__}.{m.name}"), "TOOL", None)
        if cls is not None:
            found.append(cls)
    return sorted(found, key=lambda c: (getattr(c, "order", 0), c.name))

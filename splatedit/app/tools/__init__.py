"""The editor's tools: each owns its mouse input, its keymap actions, its
overlay drawing and its help entries (:class:`~splatedit.app.tools.base.Tool`).

* :class:`~splatedit.app.tools.camera.CameraTool`: orbit / pan / dolly / zoom,
  framing, numpad views about the up axis;
* :class:`~splatedit.app.tools.brush.BrushTool`: support / handle painting
  and the selection tools (grow, shrink, connected, invert, closure);
* :class:`~splatedit.app.tools.gizmo.GizmoTool`: the handle gizmo (arrows,
  rings, scale grip) and G/R/S manipulations with their live readout;
* :class:`~splatedit.app.tools.curve.CurveTool`: the control curve.
"""

"""splatedit.app: the interactive editor (``splatedit edit [FILE]``).

Modules (the pure ones are unit-tested without a window or GPU):

* :mod:`~splatedit.app.editor` - the thin main loop: window events go to the
  tools, keys through the keymap to actions; entry point
  :func:`~splatedit.app.editor.run_editor`.
* :mod:`~splatedit.app.tools` - the tools, each owning its mouse input, its
  actions, its overlay and its help entries: camera, brush (selection tools),
  gizmo (G/R/S, live readout), curve.
* :mod:`~splatedit.app.ui.keymap` - the one declarative table of key and mouse
  bindings; generates the F1 help, ``splatedit edit --help`` and the manual's
  controls list (pure).
* :mod:`~splatedit.app.view.frames` - frame scheduling: interactive / full
  quality / background refinement, overlay compositing, present.
* :mod:`~splatedit.app.ui.panel` - the status panel (placed off the gizmo), the
  paged F1 help window, progress bars, questions.
* :mod:`~splatedit.app.ui.status` - the ``--status-file`` test hook.
* :mod:`~splatedit.app.document.files` - model checks, loading, saving, exporting.
* :mod:`~splatedit.app.document.session` - the document: selection, edits, history,
  edit-script export; with :mod:`~splatedit.app.document.rig` (pose, curve),
  :mod:`~splatedit.app.document.fitting` (background fits, :class:`FitStats`) and
  :mod:`~splatedit.app.document.manipulation` (a G/R/S move and its readout) (pure).
* :mod:`~splatedit.app.document.revision` - revision numbers, the cache keys that
  replace ``id()``.
* :mod:`~splatedit.app.tools.pick_brush` - screen-space brush on pick maps (pure); the
  selection itself is :class:`splatedit.select.selection.Selection`.
* :mod:`~splatedit.app.view.camera_control` - turntable orbit/pan/dolly-to-cursor
  camera about an up axis (pure numpy).
* :mod:`~splatedit.app.document.history` - undo snapshots (pure).
* :mod:`~splatedit.app.view.viewport` - renderer(s), levels of detail, frame
  budget, background refinement; :class:`FrameInfo` of the last frame.
* :mod:`~splatedit.app.ui.overlay` - Pillow text panels composited on the CPU.
* :mod:`~splatedit.bench.editor` - :func:`bench_editor_frames` (``splatedit bench editor``).

Presenting uses :mod:`splatedit.render.vk.window` (glfw, no client API) and
:mod:`splatedit.render.vk.swapchain` (Vulkan swapchain fed from numpy frames).
"""

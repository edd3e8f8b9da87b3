"""splatedit.app: the interactive editor (``splatedit edit [FILE]``).

Modules (the pure ones are unit-tested without a window or GPU):

* :mod:`~splatedit.app.editor` - the window, input mapping, overlay, main
  loop; entry point :func:`~splatedit.app.editor.run_editor`; the key and
  mouse bindings are :data:`~splatedit.app.editor.CONTROLS`.
* :mod:`~splatedit.app.session` - document state machine: selection ->
  background fit -> G/R/S manipulation -> commit/cancel, undo/redo, edit
  script export (pure).
* :mod:`~splatedit.app.brush` - screen-space brush on pick maps (pure).
* :mod:`~splatedit.app.camera_control` - turntable orbit/pan/dolly-to-cursor
  camera (pure numpy).
* :mod:`~splatedit.app.history` - undo snapshots (pure).
* :mod:`~splatedit.app.viewport` - renderer(s), levels of detail, frame
  budget, background refinement.
* :mod:`~splatedit.app.overlay` - Pillow text panels composited on the CPU.
* :mod:`~splatedit.app.bench` - :func:`bench_editor_frames` (``splatedit bench editor``).

Presenting uses :mod:`splatedit.render.vk.window` (glfw, no client API) and
:mod:`splatedit.render.vk.swapchain` (Vulkan swapchain fed from numpy frames).
"""

"""The editor's view: the orbit camera, the viewport's scenes, frame scheduling and progressive refinement."""

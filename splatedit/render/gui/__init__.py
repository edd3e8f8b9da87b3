"""Dear ImGui drawn by our own Vulkan pipeline: the GUI object, glfw input routing and the demo window."""

"""The editor's interface: keymap, event routing, Dear ImGui menus and panels, CPU overlays, status file, options."""

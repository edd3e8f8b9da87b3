"""The editor's document: the edit session, its rig, history, fits, jobs and recovery (no window, no GPU)."""

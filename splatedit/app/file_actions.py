"""The editor's file actions: loading, opening (the file browser, a path,
a dropped file, the recent files), the save-as prompt, saving, exporting the
edit script and quitting with unsaved changes.

A part of :class:`~splatedit.app.editor.Editor` (mixed into it; the state
it uses -- ``path``, ``jobs``, ``prompt``, ``confirm_quit``, ``saved_path``
... -- is the editor's, read by the panels and the status file).  The work
itself (worker jobs, checks, error boxes) is in :mod:`splatedit.app.document.files`;
these are the entry points keys, the GUI's File menu and drops call.
"""

from __future__ import annotations

from pathlib import Path

from splatedit.app.document import files
from splatedit.errors import SplatEditError


class FileActions:
    """Load / open / save / export / quit of the Editor (its File menu API)."""

    # -------------------------------------------------------------- loading
    def start_load(self) -> None:
        self.jobs["load"] = files.load_job(self.path, self.wake, getattr(self, "out_of_core", None))

    def on_loaded(self, cloud, path=None) -> None:
        files.on_loaded(self, cloud, path)

    # ------------------------------------------- opening (also the GUI's File menu)
    def open_dialog(self, folder=None) -> None:
        """Show the file browser (Ctrl+O) in ``folder`` (default: the model's);
        a G/R/S move in progress is cancelled first."""
        if self.session is not None and self.session.manip is not None:
            self.gizmo.cancel_manip()
        self.confirm_quit = False
        self.prompt = None
        self.browser.open(folder)

    def open_path(self, path, confirmed: bool = False) -> bool:
        """Open the model at ``path`` in place of the current one (asks first
        with unsaved changes unless ``confirmed``); True when loading started."""
        return files.open_path(self, path, confirmed=confirmed)

    def answer_open(self, yes: bool) -> None:
        """The answer to "open without saving?" (Y / N keys, the question's buttons)."""
        files.answer_open(self, yes)

    def recent_files(self) -> list[Path]:
        """The recent models, most recent first (missing files dropped)."""
        return [] if self.recent is None else self.recent.files()

    def clear_recent(self) -> None:
        """Forget the recent files (File > Open recent > Clear recent files)."""
        if self.recent is None:
            return
        try:
            self.recent.clear()
            self.say("recent files cleared")
        except SplatEditError as exc:
            self.say(f"recent files not cleared: {exc}")

    def poll_jobs(self) -> None:
        files.poll_jobs(self)

    # ------------------------------------------------------- save-as prompt
    def prompt_key(self, k: int, mods: int = 0) -> None:
        """A key while the save-as path is typed: Enter saves, Esc cancels,
        Backspace deletes the last character (the whole text once Ctrl+A
        selected it), Ctrl+A selects all (typing then replaces it),
        Ctrl+Backspace / Ctrl+U clear the path."""
        g = self.g
        ctrl = bool(mods & g.MOD_CONTROL)
        if k in (g.KEY_ENTER, g.KEY_KP_ENTER):
            path, self.prompt = self.prompt.strip(), None
            if path:
                self.save(Path(path).expanduser())
        elif k == g.KEY_ESCAPE:
            self.prompt = None
        elif ctrl and k == g.KEY_A:
            self.prompt_selected = bool(self.prompt)
        elif (ctrl and k in (g.KEY_BACKSPACE, g.KEY_U)) or (k == g.KEY_BACKSPACE and self.prompt_selected):
            self.prompt, self.prompt_selected = "", False
        elif k == g.KEY_BACKSPACE:
            self.prompt = self.prompt[:-1]
        elif k in (g.KEY_LEFT, g.KEY_RIGHT, g.KEY_HOME, g.KEY_END):
            self.prompt_selected = False       # no cursor movement: the selection ends
        # other keys (a character's own key press, modifiers) leave the selection: the
        # character event that follows replaces the selected path

    def prompt_char(self, char: str) -> None:
        """A typed character: appended to the path (replaces it when selected)."""
        if char.isprintable():
            self.prompt = char if self.prompt_selected else self.prompt + char
            self.prompt_selected = False

    # ------------------------------------------------------------- saving
    def save_target(self) -> Path:
        if self.save_as is not None:
            return self.save_as
        if self.saved_path is not None:
            return self.saved_path
        self.save_as = files.default_save_path(self.path, self.cloud_name, self.bundled)
        return self.save_as

    save = files.save

    def save_edits(self) -> None:
        """Ctrl+S: save to :meth:`save_target`; with no edit (nothing but a
        selection changed) or nothing new since the last save, say so instead
        of writing a copy of the model."""
        s = self.session
        if s is None:
            return
        if not s.edits:
            self.say("nothing to save (no edits)")
            return
        if not s.dirty and self.saved_path is not None:
            self.say(f"nothing to save (no changes since it was saved to {self.saved_path.name})")
            return
        self.save(self.save_target())

    def ask_save_as(self) -> None:
        self.prompt = str(self.save_target())
        self.prompt_selected = False

    def export_script(self) -> None:
        files.export_script(self, self.save_target())

    def answer_quit(self, yes: bool) -> None:
        """The answer to "quit without saving?": yes quits, no stays."""
        if yes:
            self.running = False
        else:
            self.confirm_quit = False
            self.say("quit cancelled")

    def request_quit(self) -> None:
        s = self.session
        if s is not None and s.dirty and not self.confirm_quit:
            self.confirm_quit = True
            self.say("unsaved changes: press Y (or Q) to quit without saving, N or Esc to stay")
        else:
            self.running = False

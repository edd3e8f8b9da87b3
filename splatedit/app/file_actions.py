"""The editor's file actions: loading, opening (the file browser, a path,
a dropped file, the recent files), the save-as prompt, saving, exporting the
edit script and quitting with unsaved changes.

An owned part of :class:`~splatedit.app.editor.Editor`
(``editor.file_actions``, a :class:`FileActions`; the state it uses --
``path``, ``jobs``, ``prompt``, ``confirm_quit``, ``saved_path`` ... -- is the
editor's, read by the panels and the status file).  The work
itself (worker jobs, checks, error boxes) is in :mod:`splatedit.app.document.files`;
these are the entry points keys, the GUI's File menu and drops call.
"""

from __future__ import annotations

from pathlib import Path

from splatedit.app.document import files
from splatedit.errors import SplatEditError


class FileActions:
    """Load / open / save / export / quit of the Editor (its File menu API;
    ``ed``: the :class:`~splatedit.app.editor.Editor`)."""

    def __init__(self, ed):
        self.ed = ed

    # -------------------------------------------------------------- loading
    def start_load(self) -> None:
        self.ed.jobs["load"] = files.load_job(self.ed.path, self.ed.wake, getattr(self.ed, "out_of_core", None))

    def on_loaded(self, cloud, path=None) -> None:
        files.on_loaded(self.ed, cloud, path)

    # ------------------------------------------- opening (also the GUI's File menu)
    def open_dialog(self, folder=None) -> None:
        """Show the file browser (Ctrl+O) in ``folder`` (default: the model's);
        a G/R/S move in progress is cancelled first."""
        if self.ed.session is not None and self.ed.session.manip is not None:
            self.ed.gizmo.cancel_manip()
        self.ed.confirm_quit = False
        self.ed.prompt = None
        self.ed.browser.open(folder)

    def open_path(self, path, confirmed: bool = False) -> bool:
        """Open the model at ``path`` in place of the current one (asks first
        with unsaved changes unless ``confirmed``); True when loading started."""
        return files.open_path(self.ed, path, confirmed=confirmed)

    def answer_open(self, yes: bool) -> None:
        """The answer to "open without saving?" (Y / N keys, the question's buttons)."""
        files.answer_open(self.ed, yes)

    def recent_files(self) -> list[Path]:
        """The recent models, most recent first (missing files dropped)."""
        return [] if self.ed.recent is None else self.ed.recent.files()

    def clear_recent(self) -> None:
        """Forget the recent files (File > Open recent > Clear recent files)."""
        if self.ed.recent is None:
            return
        try:
            self.ed.recent.clear()
            self.ed.say("recent files cleared")
        except SplatEditError as exc:
            self.ed.say(f"recent files not cleared: {exc}")

    def poll_jobs(self) -> None:
        files.poll_jobs(self.ed)

    # ------------------------------------------------------- save-as prompt
    def prompt_key(self, k: int, mods: int = 0) -> None:
        """A key while the save-as path is typed: Enter saves, Esc cancels,
        Backspace deletes the last character (the whole text once Ctrl+A
        selected it), Ctrl+A selects all (typing then replaces it),
        Ctrl+Backspace / Ctrl+U clear the path."""
        g = self.ed.g
        ctrl = bool(mods & g.MOD_CONTROL)
        if k in (g.KEY_ENTER, g.KEY_KP_ENTER):
            path, self.ed.prompt = self.ed.prompt.strip(), None
            if path:
                self.save(Path(path).expanduser())
        elif k == g.KEY_ESCAPE:
            self.ed.prompt = None
        elif ctrl and k == g.KEY_A:
            self.ed.prompt_selected = bool(self.ed.prompt)
        elif (ctrl and k in (g.KEY_BACKSPACE, g.KEY_U)) or (k == g.KEY_BACKSPACE and self.ed.prompt_selected):
            self.ed.prompt, self.ed.prompt_selected = "", False
        elif k == g.KEY_BACKSPACE:
            self.ed.prompt = self.ed.prompt[:-1]
        elif k in (g.KEY_LEFT, g.KEY_RIGHT, g.KEY_HOME, g.KEY_END):
            self.ed.prompt_selected = False       # no cursor movement: the selection ends
        # other keys (a character's own key press, modifiers) leave the selection: the
        # character event that follows replaces the selected path

    def prompt_char(self, char: str) -> None:
        """A typed character: appended to the path (replaces it when selected)."""
        if char.isprintable():
            self.ed.prompt = char if self.ed.prompt_selected else self.ed.prompt + char
            self.ed.prompt_selected = False

    # ------------------------------------------------------------- saving
    def save_target(self) -> Path:
        if self.ed.save_as is not None:
            return self.ed.save_as
        if self.ed.saved_path is not None:
            return self.ed.saved_path
        self.ed.save_as = files.default_save_path(self.ed.path, self.ed.cloud_name, self.ed.bundled)
        return self.ed.save_as

    def save(self, path: Path) -> None:
        """Save the edited model to ``path`` in the background (:func:`splatedit.app.document.files.save`)."""
        files.save(self.ed, path)

    def save_edits(self) -> None:
        """Ctrl+S: save to :meth:`save_target`; with no edit (nothing but a
        selection changed) or nothing new since the last save, say so instead
        of writing a copy of the model."""
        s = self.ed.session
        if s is None:
            return
        if not s.edits:
            self.ed.say("nothing to save (no edits)")
            return
        if not s.dirty and self.ed.saved_path is not None:
            self.ed.say(f"nothing to save (no changes since it was saved to {self.ed.saved_path.name})")
            return
        self.save(self.save_target())

    def ask_save_as(self) -> None:
        self.ed.prompt = str(self.save_target())
        self.ed.prompt_selected = False

    def export_script(self) -> None:
        files.export_script(self.ed, self.save_target())

    def answer_quit(self, yes: bool) -> None:
        """The answer to "quit without saving?": yes quits, no stays."""
        if yes:
            self.ed.running = False
        else:
            self.ed.confirm_quit = False
            self.ed.say("quit cancelled")

    def request_quit(self) -> None:
        s = self.ed.session
        if s is not None and s.dirty and not self.ed.confirm_quit:
            self.ed.confirm_quit = True
            self.ed.say("unsaved changes: press Y (or Q) to quit without saving, N or Esc to stay")
        else:
            self.ed.running = False

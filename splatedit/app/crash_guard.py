"""No internal error takes the editor's window down (issue 19 item 1).

An object the :class:`~splatedit.app.editor.Editor` owns (``editor.crash_guard``).  The loop
dispatches work in a few places -- each window event
(:meth:`~splatedit.app.ui.routing.EventRouter.handle_events`), the landing of
finished jobs (load, save, levels of detail, graph), the session's poll
(fits and background commits landing), each frame (scene, GUI and its
buttons' actions, present) and the status file -- and each runs inside
:meth:`CrashGuard.guarded`.  An exception there that is not a
:class:`~splatedit.errors.SplatEditError` (those are the user's messages,
handled where they arise) is a bug; the guard

* prints its traceback on stderr,
* cancels a running G/R/S move and drag (they may be half done; the
  document is not touched: every document change is one history step),
* writes a recovery entry (:mod:`splatedit.app.document.recovery`) when there are
  unsaved edits (once per history state),
* shows the error box: what failed, that the document is kept and where
  the recovery copy is.

The process ending by SIGTERM or Ctrl+C (KeyboardInterrupt) with unsaved
edits, or an exception escaping the loop anyway, writes a recovery entry
too (:meth:`CrashGuard.recover_on_exit`).  At the next start
:meth:`CrashGuard.offer_recovery` asks Restore / Discard (Esc: ask again
next time).
"""

from __future__ import annotations

import contextlib
import sys
import traceback
from pathlib import Path

from splatedit.app.document import recovery
from splatedit.app.document import revision
from splatedit.app.tools.base import DragMode
from splatedit.errors import SplatEditError


class CrashGuard:
    """Central exception guard, recovery files and the restore question of an editor.

    Args:
        ed: the editor it guards.  The guard reads its document (``session``,
            ``path``, ``bundled``), reports through ``say`` and ``show_error``,
            cancels its drag (``drag``, ``drag_tool``) and, restoring, opens
            the recovered model (``open_path``) and sets ``cloud_name`` and
            ``save_as``.
    """

    def __init__(self, ed):
        self.ed = ed
        #: the recovery entry the restore question is about (None: no question)
        self.confirm_restore = None
        #: the entry being restored (its load is running), then the restored one until it is saved
        self.restoring = None
        self.restored = None
        self._recovery_key = None
        self._recovery_entry = None      # the copy this run wrote last (a newer one replaces it)
        self._last_internal = None
        #: internal errors met so far (the status file shows it; tests wait for it)
        self.internal_errors = 0

    # ------------------------------------------------------------- the guard
    @contextlib.contextmanager
    def guarded(self, what: str):
        """Run the block; a SplatEditError (a user's message) goes to the
        status line, any other exception is a bug: :meth:`internal_error`."""
        try:
            yield
        except SplatEditError as exc:
            self.ed.say(str(exc))
        except Exception as exc:  # noqa: BLE001 - the point: nothing takes the window down
            self.internal_error(what, exc)

    def internal_error(self, what: str, exc: BaseException) -> None:
        """Report a bug met while ``what`` (traceback on stderr, error box),
        keep the document, write a recovery entry when there are unsaved edits."""
        self.internal_errors += 1
        sig = (what, type(exc).__name__, str(exc))
        if sig != self._last_internal:      # the same error every frame: one traceback
            print(f"splatedit: internal error while {what}:", file=sys.stderr)
            traceback.print_exception(type(exc), exc, exc.__traceback__, file=sys.stderr)
            sys.stderr.flush()
        self._last_internal = sig
        with contextlib.suppress(Exception):
            self._reset_transient_state()
        saved = self.recovery_note(f"internal error while {what}: {type(exc).__name__}: {exc}")
        self.ed.show_error(f"internal error while {what}: {type(exc).__name__}: {exc}. "
                        f"The document is kept{saved}; details on stderr")

    def _reset_transient_state(self) -> None:
        """A running move or drag may be half done: cancel it (the document
        itself only changes in whole history steps)."""
        ed = self.ed
        s = ed.session
        if s is not None and s.manip is not None:
            s.cancel()
        ed.drag, ed.drag_tool = DragMode.NONE, None

    # -------------------------------------------------------------- recovery
    def write_recovery(self, reason: str):
        """Write the document as a recovery entry (once per history state);
        the entry, or None when nothing is unsaved or it was written already."""
        ed = self.ed
        s = ed.session
        if s is None or not s.edits or not s.dirty:
            return None
        key = (id(s), revision.of(s.cloud), s.history.position, len(s.edits))
        if key == self._recovery_key:
            return None
        src = self.restored.source if self.restored is not None else (None if ed.path is None else str(ed.path))
        entry = recovery.write_recovery(s, src, bundled=ed.bundled, reason=reason)
        self._recovery_key = key
        if entry is not None:
            if self._recovery_entry is not None:    # this run's older copy: the new one supersedes it
                recovery.discard(self._recovery_entry)
            self._recovery_entry = entry
            print(f"splatedit: recovery copy written: {entry.model} (edit script {entry.script.name})",
                  file=sys.stderr, flush=True)
        return entry

    def recovery_note(self, reason: str) -> str:
        """Write a recovery entry and say where, for a message ("" when none was needed)."""
        try:
            entry = self.write_recovery(reason)
        except Exception as exc:  # noqa: BLE001 - a failing recovery must not hide the first error
            print(f"splatedit: recovery copy not written: {exc}", file=sys.stderr, flush=True)
            return f" (a recovery copy could not be written: {exc})"
        if entry is None:
            return ""
        return f"; a recovery copy of it is in {entry.model.parent} (offered at the next start)"

    def recover_on_exit(self, reason: str) -> None:
        """The process is ending abnormally (SIGTERM, Ctrl+C, an exception out of the loop)."""
        try:
            self.write_recovery(reason)
        except Exception as exc:  # noqa: BLE001
            print(f"splatedit: recovery copy not written: {exc}", file=sys.stderr, flush=True)

    # --------------------------------------------------- restoring at start
    def offer_recovery(self) -> bool:
        """At start: ask whether to restore the newest recovery entry (True when asked)."""
        got = recovery.entries()
        if not got:
            return False
        self.confirm_restore = got[0]
        e = got[0]
        more = f" ({len(got) - 1} older in {e.manifest.parent})" if len(got) > 1 else ""
        self.ed.say(f"a recovery copy of {e.name} from {e.when()} ({e.edits} edit(s)): "
                 f"Y restores it, N discards it, Esc asks again next time{more}")
        return True

    def answer_restore(self, answer: bool | None) -> None:
        """True: open the recovered document; False: delete the entry; None: keep it for next time."""
        entry, self.confirm_restore = self.confirm_restore, None
        if entry is None:
            return
        if answer is None:
            self.ed.say(f"the recovery copy stays in {entry.manifest.parent} (asked again at the next start)")
            return
        if not answer:
            recovery.discard(entry)
            self.ed.say(f"recovery copy of {entry.name} discarded")
            return
        if self.ed.file_actions.open_path(entry.model, confirmed=True):
            self.restoring = entry

    def on_restored(self) -> None:
        """The recovered model finished loading: adopt its edits and its source (for Ctrl+S)."""
        entry, self.restoring = self.restoring, None
        ed = self.ed
        s = ed.session
        try:
            from splatedit.script import load_script
            script = load_script(entry.script)
        except SplatEditError as exc:
            ed.show_error(f"the recovery copy's edit script cannot be read ({exc}); the model is "
                            f"open without it: save it as a new file")
            return
        s.adopt_recovered(script, f"Recovered {len(script.edits)} edit(s)")
        if entry.source:            # saves go beside the source (never onto it), as before the crash
            ed.path, ed.bundled = Path(entry.source), entry.bundled
        ed.cloud_name = entry.name
        ed.save_as = None
        self.restored = entry
        ed.say(f"restored {entry.name} from {entry.when()} with {len(script.edits)} edit(s): "
                 f"Ctrl+S saves it")

    def restored_saved(self, session) -> None:
        """A save of the restored document finished: its recovery entry is no longer needed."""
        if self.restored is not None and session is self.ed.session:
            recovery.discard(self.restored)
            self.restored = None

"""Delete and crop selected splats (a scan's stray points, a floor): Delete
removes the support splats from the document, Shift+Delete (Select > Crop)
keeps only them.  One undo step each, recorded in the edit script as a
``delete`` / ``crop`` item (:mod:`splatedit.script`), so ``splatedit
deform`` replaying a saved script gives the saved file.

A tool on the narrow protocol (:attr:`Tool.ctx` only).
"""

from __future__ import annotations

from splatedit.app.ui.keymap import Action, Section
from splatedit.app.tools.base import Tool


class DeleteTool(Tool):
    section = Section.SELECTION
    #: the editor attribute it is reachable as (``editor.delete``)
    name = "delete"

    def actions(self):
        return {Action.DELETE_SPLATS: lambda: self.remove(keep=False),
                Action.CROP_SPLATS: lambda: self.remove(keep=True)}

    def remove(self, keep: bool) -> int:
        """Delete (``keep`` False) or crop to the support; the splats removed."""
        c = self.ctx
        doc = c.document
        what = "crop" if keep else "delete"
        sup = int(doc.selection.support.sum())
        if sup == 0:
            c.say(f"{what}: paint the {c.items} to {'keep' if keep else 'remove'} as support first (1)")
            return 0
        if doc.pose_pending or doc.manip is not None:
            c.say(f"{what}: apply or discard the pending moves first (Enter / Esc)")
            return 0
        if doc.splats_fixed:
            c.say(f"{what}: {doc.splats_fixed}")
            return 0
        if sup == doc.cloud.n:
            c.say(f"{what}: the support is the whole model: nothing would " + ("change" if keep else "be left"))
            return 0
        n = doc.remove_splats(keep)
        if n:
            c.say(f"{what}: removed {n:,} {c.items}, {doc.cloud.n:,} left (Ctrl+Z undoes it)")
        return n


TOOL = DeleteTool

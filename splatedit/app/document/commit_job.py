"""An edit's commit as background work (issue 10: long work shows progress,
the window stays responsive).

:meth:`Session.commit <splatedit.app.document.session_pose.PoseEditing.commit>` freezes the pose into
a :class:`CommitPlan` (the basis, the base cloud, the pose's dC and the
script edit it records).  A commit estimated to take less than
``EDITOR_COMMIT_SYNC_MS`` (:func:`estimate_ms`) is applied at once on the
UI thread; a longer one runs as a :class:`~splatedit.app.document.jobs.Job` (the
fits' machinery) while the viewport keeps drawing the frozen pose on the
GPU.  The job only computes the new cloud: the document (cloud, edits,
history) changes when :meth:`Session.poll` lands it on the UI thread, as one
undo step.  An error (a degenerate splat) leaves the document as it was; a
cancelled job (the session closed) leaves nothing behind.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from splatedit.app.document.gaussian import commit_cloud, gaussians_of
from splatedit.app.document.jobs import Cancelled, Job
from splatedit.deform.basis import APPLY_STAGE, CHECK_STAGE
from splatedit.deform.gaussians import GAUSSIAN_STAGE
from splatedit.errors import SplatEditError
from splatedit.tolerances import (EDITOR_COMMIT_US_PER_SPLAT, EDITOR_COMMIT_US_PER_SUPPORT_GAUSSIAN,
                                  EDITOR_COMMIT_US_PER_SUPPORT_SPLAT)

#: the name of a commit job (its first progress stage)
COMMIT_JOB = "applying the edit"


#: the last stage of a commit: the edit script's index lists (and, for
#: Gaussians, the new proxy splats) after the deformation
RECORD_STAGE = "recording the edit"
#: the part of a whole commit each stage covers (measured: the check is
#: 0.11-0.18 s of 1.2-2.4 s for 1M splats with a 333k support; the proxy
#: splats of 100k Gaussians 0.09 s of 0.8-1.0 s)
STAGE_SPANS = {APPLY_STAGE: (0.0, 0.85), CHECK_STAGE: (0.85, 0.95), GAUSSIAN_STAGE: (0.0, 0.9),
               RECORD_STAGE: (0.95, 1.0)}


def _overall(progress):
    """``progress`` fed the fraction of the whole commit instead of the stage's."""
    def report(stage: str, fraction: float) -> None:
        lo, hi = STAGE_SPANS.get(stage, (0.0, 1.0))
        progress(stage, lo + (hi - lo) * fraction)
    return report


@dataclass(frozen=True)
class CommitPlan:
    """One edit frozen at Enter / release, ready to be applied.

    ``basis``: the fitted DeformationBasis or DetailBasis; ``cloud``: the
    base document (a SplatCloud, maybe with Gaussians attached) it was
    fitted on; ``dc``: (K, 3) float64 or a RotationDisplacement (the whole
    pose); ``make_edit``: builds the :class:`~splatedit.script.Edit` recorded
    when it lands (index lists of up to millions of splats: built off the UI
    thread); ``handles``: the number of handles (the pose is reset to them);
    ``label``: the edit's name in the history list."""
    basis: object
    cloud: object
    dc: object
    make_edit: object
    handles: int
    label: str = "Edit"
    #: the edit's DeformationMode (None: the basis' result as it is) and the
    #: handles' (4, 4) maps: a translation with needles in the rotation mode
    #: is refined (splatedit.deform.refine); ``outcome["refined"]`` then
    #: holds its note (set by :meth:`work`)
    mode: object = None
    matrices: tuple = ()
    outcome: dict = field(default_factory=dict)

    def work(self, progress=None):
        """The deformed document (``commit_cloud``); ``progress(stage,
        fraction)`` after each chunk.  Raises InputError on a degenerate splat."""
        return commit_cloud(self.basis, self.cloud, self.dc, progress=progress, mode=self.mode,
                            matrices=self.matrices, outcome=self.outcome)

    def run(self, progress=None):
        """``(deformed document, script Edit)``: what a commit job computes;
        ``progress(stage, fraction)`` gets the fraction of the whole commit
        (:data:`STAGE_SPANS`: never decreasing across stages)."""
        report = None if progress is None else _overall(progress)
        new = self.work(report)
        if report is not None:
            report(RECORD_STAGE, 0.0)
        edit = self.make_edit()
        if report is not None:
            report(RECORD_STAGE, 1.0)
        return new, edit

    def estimate_ms(self) -> float:
        """:func:`estimate_ms` of this plan."""
        return estimate_ms(self.cloud, len(self.basis.indices))


def estimate_ms(cloud, support: int) -> float:
    """Estimated milliseconds of a commit of ``support`` splats (Gaussians)
    of ``cloud`` on this kind of machine (the figures in splatedit/tolerances/app.py)."""
    per = (EDITOR_COMMIT_US_PER_SUPPORT_GAUSSIAN if gaussians_of(cloud) is not None
           else EDITOR_COMMIT_US_PER_SUPPORT_SPLAT)
    return 1e-3 * (per * support + EDITOR_COMMIT_US_PER_SPLAT * cloud.n)


@dataclass(frozen=True)
class CommitProgress:
    """A running commit: its stage, fraction done (0..1) and seconds so far."""
    stage: str
    fraction: float
    elapsed: float


@dataclass(frozen=True)
class CommitOutcome:
    """How a background commit ended, for the editor to show once:
    ``error`` (None: applied) and the seconds it took."""
    error: str | None
    seconds: float
    edits: int


class CommitRunner:
    """At most one background commit of a session: start, progress, collect, cancel."""

    def __init__(self, on_change=None):
        self.on_change = on_change or (lambda: None)
        self.job: Job | None = None
        self.plan: CommitPlan | None = None

    @property
    def running(self) -> bool:
        return self.job is not None

    def start(self, plan: CommitPlan) -> None:
        """Run ``plan`` in a daemon thread; :attr:`on_change` is called when it ends."""
        self.plan = plan
        self.job = Job(COMMIT_JOB, plan.run, self.on_change)

    def progress(self) -> CommitProgress | None:
        j = self.job
        return None if j is None else CommitProgress(j.stage, j.fraction, time.perf_counter() - j.started)

    def collect(self):
        """``(plan, (new cloud, edit), error message or None, seconds)`` of a
        finished job (None while none finished; a cancelled one is dropped)."""
        j = self.job
        if j is None or not j.done:
            return None
        plan, self.job, self.plan = self.plan, None, None
        seconds = time.perf_counter() - j.started
        exc = j.error
        if exc is None:
            return plan, j.result, None, seconds
        if isinstance(exc, Cancelled):
            return None
        if isinstance(exc, SplatEditError):
            return plan, None, str(exc), seconds
        return plan, None, f"internal error while applying the edit: {exc!r}", seconds

    def cancel(self) -> None:
        """Abandon the running commit (it ends at its next chunk; nothing is kept)."""
        if self.job is not None:
            self.job.cancel.set()
            self.job = self.plan = None

    def wait(self, timeout: float | None = None) -> bool:
        """Block until the running commit is done (tests); True when none is left running."""
        return self.job is None or self.job.wait(timeout)

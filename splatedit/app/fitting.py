"""Fit scheduling of an edit session: one background fit of the rig's basis
at a time (restarted when the selection or the curve changes, cancelled
fits end at their next progress report), its result, its error, and the
solver figures the panel shows (:class:`FitStats`)."""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

from splatedit.app.jobs import Cancelled, Job
from splatedit.errors import SplatEditError


@dataclass(frozen=True)
class FitStats:
    """Figures of the fitted basis (None before a fit finished)."""
    method: str | None
    centers: int | None
    constraints: int | None
    residual: float | None
    fit_seconds: float | None
    basis_seconds: float | None
    columns: int

    @classmethod
    def of(cls, basis) -> "FitStats":
        st = basis.stats if isinstance(basis.stats, dict) else vars(basis.stats)
        return cls(st.get("method"), st.get("n_centers"), st.get("n_constraints"), st.get("residual"),
                   st.get("fit_seconds"), st.get("basis_seconds"), int(basis.n_columns))


@dataclass(frozen=True)
class FitProgress:
    """A running fit: its stage, fraction done (0..1) and seconds so far."""
    stage: str
    fraction: float
    elapsed: float


class FitScheduler:
    """Runs fits one at a time on its own worker (``sync``: on the calling
    thread, tests) and keeps the last result.

    ``basis`` is the fitted :class:`~splatedit.deform.basis.DeformationBasis`
    of ``key`` (the selection key it was fitted for) and ``groups`` its
    ``(fitted handle indices, ControlCurve or None)``."""

    def __init__(self, *, sync: bool = False, on_change=None):
        self.sync = sync
        self.on_change = on_change or (lambda: None)
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="splatedit-fit")
        self.job: Job | None = None
        self.basis = None
        self.key = None
        self.groups = None
        self.error: str | None = None

    def current(self, key) -> bool:
        """The basis (or the running fit) is for ``key``."""
        return (self.basis is not None and self.key == key) or (self.job is not None and self.job.key == key)

    def clear(self) -> None:
        """Forget the basis and the error, cancel a running fit."""
        if self.job is not None:
            self.job.cancel.set()
            self.job = None
        self.basis = self.key = self.groups = None
        self.error = None

    def start(self, key, groups, work) -> None:
        """Start fitting ``work(progress) -> basis`` for selection ``key``."""
        job = Job("fitting", work, None if self.sync else self.on_change, key=key, executor=self._pool,
                  sync=self.sync)
        job.groups = groups
        self.job = job

    def poll(self, current_key) -> bool | None:
        """Collect a finished fit.  Returns None when it was for another key
        than ``current_key`` (the caller restarts), else True when the state
        changed."""
        job = self.job
        if job is None or not job.done:
            return False
        self.job = None
        if job.key != current_key:
            return None
        exc = job.error
        if exc is None:
            self.basis, self.key, self.groups = job.result, job.key, job.groups
        elif isinstance(exc, Cancelled):
            return False
        elif isinstance(exc, SplatEditError):
            self.error = str(exc)
        else:   # a bug (its traceback is printed by the job), but keep the editor alive
            self.error = f"internal error while fitting: {exc!r}"
        return True

    def stats(self) -> FitStats | None:
        return None if self.basis is None else FitStats.of(self.basis)

    def progress(self) -> FitProgress | None:
        j = self.job
        return None if j is None else FitProgress(j.stage, j.fraction, time.perf_counter() - j.started)

    def close(self) -> None:
        if self.job is not None:
            self.job.cancel.set()
        self._pool.shutdown(wait=False, cancel_futures=True)

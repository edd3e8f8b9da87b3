"""Fit scheduling of an edit session: one background fit of the rig's basis
at a time (restarted when the selection or the curve changes, cancelled
fits end at their next progress report), its result, its error, and the
solver figures the panel shows (:class:`FitStats`)."""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

from splatedit.app.document.jobs import Cancelled, Job
from splatedit.deform.modes import DeformationMode
from splatedit.errors import SplatEditError


def fitted_kind(mode: DeformationMode) -> str:
    """The basis a deformation mode draws with: ``"detail"`` (a
    :class:`~splatedit.deform.detail.DetailBasis`: base surface + offsets) for
    DETAIL, ``"plain"`` (a :class:`~splatedit.deform.basis.DeformationBasis`)
    for LINEAR and ROTATION, which share one fit (switching between them
    needs no refit)."""
    return "detail" if DeformationMode(mode) is DeformationMode.DETAIL else "plain"


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


def basis_bytes(basis) -> int:
    """The bytes of the arrays a fitted basis holds (its own attributes, one
    level deep, and the arrays of its constraints and CPU cache)."""
    import numpy as np
    total, seen = 0, set()

    def add(v) -> None:
        nonlocal total
        if isinstance(v, np.ndarray) and id(v) not in seen:
            seen.add(id(v))
            total += v.base.nbytes if isinstance(v.base, np.ndarray) and id(v.base) not in seen else v.nbytes
            if isinstance(v.base, np.ndarray):
                seen.add(id(v.base))
        elif isinstance(v, dict):
            for x in v.values():
                add(x)
        elif isinstance(v, (list, tuple)):
            for x in v:
                add(x)

    for obj in (basis, getattr(basis, "constraints", None), getattr(basis, "rbf", None)):
        if obj is not None and hasattr(obj, "__dict__"):
            for v in vars(obj).values():
                add(v)
    return total


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
    (or :class:`~splatedit.deform.detail.DetailBasis`, :func:`fitted_kind`) of
    ``key`` (the selection key it was fitted for) and ``groups`` its
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
        self._graph = None    # (positions, NeighbourGraph) of the last detail fit's cloud
        #: bases replaced since (key -> (basis, groups)), newest last: undo / redo back to
        #: their selection takes them again instead of refitting (bounded, :meth:`_stash`)
        self._kept: dict = {}

    def current(self, key) -> bool:
        """The basis (or the running fit) is for ``key``."""
        return (self.basis is not None and self.key == key) or (self.job is not None and self.job.key == key)

    def clear(self) -> None:
        """Forget the basis (kept for :meth:`recall`) and the error, cancel a running fit."""
        if self.job is not None:
            self.job.cancel.set()
            self.job = None
        if self.basis is not None:
            self._stash(self.key, self.basis, self.groups)
        self.basis = self.key = self.groups = None
        self.error = None

    def _stash(self, key, basis, groups) -> None:
        """Keep a replaced basis: at most EDITOR_FIT_KEEP_BASES of them and
        EDITOR_FIT_KEEP_BYTES in all (the oldest go first; a larger one is not kept)."""
        from splatedit.tolerances import EDITOR_FIT_KEEP_BASES, EDITOR_FIT_KEEP_BYTES
        self._kept.pop(key, None)
        if hasattr(basis, "release_cpu_cache"):
            basis.release_cpu_cache()       # rebuilt by the next commit; only B is drawn
        self._kept[key] = (basis, groups, basis_bytes(basis))
        while self._kept and (len(self._kept) > EDITOR_FIT_KEEP_BASES
                              or sum(v[2] for v in self._kept.values()) > EDITOR_FIT_KEEP_BYTES):
            self._kept.pop(next(iter(self._kept)))

    def drop_kept(self) -> None:
        """Forget the kept bases (memory back; the next undo refits)."""
        self._kept.clear()

    def recall(self, key) -> bool:
        """Take back the basis kept for ``key`` (its key includes the cloud's
        revision, the masks, the curve and the kind: it is exactly what a new
        fit would compute); True when there was one."""
        got = self._kept.pop(key, None)
        if got is None:
            return False
        self.basis, self.groups, _ = got
        self.key = key
        self.error = None
        return True

    def neighbour_graph(self, cloud):
        """The :class:`~splatedit.select.graph.NeighbourGraph` of ``cloud`` for
        the detail mode's smoothing, built on the fit worker and kept for the
        next fits of the same base cloud (called only from the worker: fits
        run one at a time).  ``NeighbourGraph.build`` of the positions, as the
        script replay builds it, so a replay reproduces the edit bitwise."""
        from splatedit.select.graph import NeighbourGraph
        got = self._graph
        if got is None or got[0] is not cloud.positions:
            got = self._graph = (cloud.positions, NeighbourGraph.build(cloud.positions))
        return got[1]

    def work(self, cloud, support, handles, curves, mode: DeformationMode, *, method: str,
             tol: float, max_centers: int | None):
        """``work(progress) -> basis`` for :meth:`start`: the basis of
        :func:`fitted_kind` (``mode``) on ``cloud`` for the (n,) bool
        ``support``, the handle masks and the ControlCurves, without closing
        the selection (the editor closes it visibly after each stroke)."""
        detail = fitted_kind(mode) == "detail"

        def work(progress):
            from splatedit.deform.basis import DeformationBasis
            kw = dict(curves=curves, method=method, tol=tol, max_centers=max_centers,
                      progress=progress, fill_holes=False)
            if not detail:
                return DeformationBasis.fit(cloud, support, handles, **kw)
            from splatedit.deform.detail import DetailBasis
            return DetailBasis.fit(cloud, support, handles, graph=self.neighbour_graph(cloud), **kw)
        return work

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

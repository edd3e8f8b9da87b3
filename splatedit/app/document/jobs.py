"""Background work of the editor: loading, levels of detail, saving, fitting.

A :class:`Job` runs ``fn(progress)`` in a daemon thread (or on an executor,
or synchronously for tests) and records its progress, result or error; the
editor's loop polls :attr:`Job.done` and never blocks on it.  Setting
:attr:`Job.cancel` makes the next ``progress`` call raise :class:`Cancelled`,
which abandons a stale job.
"""

from __future__ import annotations

import os
import threading
import time
import traceback

from splatedit.errors import SplatEditError


class Cancelled(Exception):
    """Raised inside a worker's progress callback to abandon a stale job."""


class Job:
    """``fn(progress)`` run in the background with progress and a result.

    Args:
        name: shown in the overlay (also the initial :attr:`stage`).
        fn: the work; it gets :meth:`progress` (``progress(stage, fraction)``).
        wake: called (from the worker) when the job is done.
        key: any value identifying what the job computes (stale-result checks).
        executor: run on this ``concurrent.futures`` executor instead of a new
            daemon thread (e.g. to serialise fits).
        sync: run on the calling thread (tests).

    After :attr:`done`: :attr:`result`, or :attr:`error` (the exception).
    Exceptions other than :class:`SplatEditError` and :class:`Cancelled` are
    bugs: their traceback is printed on stderr.
    """

    def __init__(self, name: str, fn, wake=None, *, key=None, executor=None, sync: bool = False):
        self.name = name
        self.stage = name
        self.fraction = 0.0
        self.key = key
        self.result = None
        self.error: BaseException | None = None
        self.started = time.perf_counter()
        self.cancel = threading.Event()
        #: ``land(job)``: run by the editor on its main thread when it collects the
        #: finished job (a tool's job, :meth:`ToolContext.start_job`); None: the
        #: editor's own handling by name
        self.land = None
        self.thread: threading.Thread | None = None
        self._done = threading.Event()
        self._wake = wake
        if sync:
            self._run(fn)
        elif executor is not None:
            executor.submit(self._run, fn)
        else:
            self.thread = threading.Thread(target=self._run, args=(fn,), name=f"splatedit-{name}",
                                           daemon=True)
            self.thread.start()

    def _run(self, fn) -> None:
        try:
            if self.cancel.is_set():   # cancelled while still queued: do not start
                raise Cancelled()
            self.result = fn(self.progress)
            _test_hold(self.name)
        except BaseException as exc:  # noqa: BLE001 - reported by whoever polls the job
            self.error = exc
            if not isinstance(exc, (SplatEditError, Cancelled)):
                traceback.print_exc()
        self._done.set()
        if self._wake:
            self._wake()

    def progress(self, stage: str, fraction: float) -> None:
        """Report progress; raises :class:`Cancelled` once :attr:`cancel` is set."""
        if self.cancel.is_set():
            raise Cancelled()
        self.stage, self.fraction = stage, fraction

    @property
    def done(self) -> bool:
        return self._done.is_set()

    def wait(self, timeout: float | None = None) -> bool:
        """Block until done (at most ``timeout`` s); True when done."""
        return self._done.wait(timeout)


def _test_hold(name: str) -> None:
    """Test hook (window tests watch the editor while a job runs): with
    ``SPLATEDIT_TEST_HOLD_JOB`` set to a prefix of the job's name and
    ``SPLATEDIT_TEST_HOLD_FILE`` to a path, a job whose work is done waits
    while that file exists (at most 120 s) before it reports done."""
    prefix, path = os.environ.get("SPLATEDIT_TEST_HOLD_JOB"), os.environ.get("SPLATEDIT_TEST_HOLD_FILE")
    if not prefix or not path or not name.startswith(prefix):
        return
    t0 = time.monotonic()
    while os.path.exists(path) and time.monotonic() - t0 < 120.0:
        time.sleep(0.02)

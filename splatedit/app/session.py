"""The edit session state machine (no window, no GPU: unit-testable).

States::

    SELECT --(handle painted)--> fit runs in a worker thread (FITTING)
    FITTING --(done)--> READY (basis available; the handle can be moved)
    READY --G/R/S or drag--> MANIPULATE (matrix changes every mouse move)
    MANIPULATE --Enter / release--> commit: the deformed cloud becomes the
        new base (the selection is kept, a new fit starts for the next edit)
    MANIPULATE --Esc / right click--> cancel (back to READY)

Every user action that changes the document (a stroke, a clear, a commit)
pushes a :class:`~splatedit.app.history.Snapshot`; undo/redo restore them
(and restart the fit for the restored selection).  Committed edits are
recorded as script edits (``indices`` support + ``indices`` handle +
``matrix`` transform) and :meth:`Session.edit_script` returns an
:class:`~splatedit.script.EditScript` with the session's solver settings, so
``splatedit deform INPUT --edit script.json`` reproduces the saved cloud.
"""

from __future__ import annotations

import math
import threading
import time
import traceback
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from splatedit.app.brush import SUPPORT, Selection
from splatedit.app.history import History, Snapshot
from splatedit.errors import SplatEditError
from splatedit.tolerances import IQR_DEFAULT_TOL

GRAB, ROTATE, SCALE = "grab", "rotate", "scale"
AXIS_NAMES = "XYZ"


class Cancelled(Exception):
    """Raised inside a worker's progress callback to abandon a stale job."""


# ------------------------------------------------------------ affine helpers
def translation(d) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = d
    return m


def rotation(axis, radians: float, center) -> np.ndarray:
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    r = np.eye(3) + math.sin(radians) * k + (1 - math.cos(radians)) * (k @ k)
    m = np.eye(4)
    m[:3, :3] = r
    c = np.asarray(center, float)
    m[:3, 3] = c - r @ c
    return m


def scaling(factors, center) -> np.ndarray:
    """Scale by ``factors`` (3,) along the world axes about ``center``."""
    s = np.diag(np.asarray(factors, float))
    m = np.eye(4)
    m[:3, :3] = s
    c = np.asarray(center, float)
    m[:3, 3] = c - s @ c
    return m


# ------------------------------------------------------------ manipulation
@dataclass
class ViewInfo:
    """What a manipulation needs to know about the view when it starts."""
    right: np.ndarray
    up: np.ndarray
    back: np.ndarray
    pivot_px: tuple[float, float]
    world_per_px: float          # at the pivot's depth


@dataclass
class Manipulation:
    """A G/R/S transform of the handle being dragged or typed.

    Mouse: grab moves the pivot with the mouse in the view plane (projected on
    the constraint axis if any); rotate turns about the view axis (or the
    constraint axis) by the angle the mouse sweeps around the pivot's pixel;
    scale multiplies by the ratio of the mouse's distances to the pivot's
    pixel (along the constraint axis only, if any).  A typed number replaces
    the mouse value: grab distance in model units (along the axis, X when
    none), rotate degrees, scale factor.
    """
    mode: str
    pivot: np.ndarray
    view: ViewInfo
    start: tuple[float, float]
    mouse: tuple[float, float] = None
    axis: int | None = None
    typed: str = ""

    def __post_init__(self):
        if self.mouse is None:
            self.mouse = self.start

    def set_axis(self, axis: int) -> None:
        """X/Y/Z key: constrain to that axis; pressing it again removes it."""
        self.axis = None if self.axis == axis else axis

    def type_char(self, ch: str) -> bool:
        if ch in "0123456789.":
            self.typed += ch
        elif ch == "-":
            self.typed = self.typed[1:] if self.typed.startswith("-") else "-" + self.typed
        else:
            return False
        return True

    def backspace(self) -> None:
        self.typed = self.typed[:-1]

    def typed_value(self) -> float | None:
        t = self.typed
        if t in ("", "-", ".", "-."):
            return None
        try:
            return float(t)
        except ValueError:
            return None

    def _axis_vec(self) -> np.ndarray:
        a = np.zeros(3)
        a[self.axis] = 1.0
        return a

    def matrix(self) -> np.ndarray:
        v = self.view
        typed = self.typed_value()
        dx = self.mouse[0] - self.start[0]
        dy = self.mouse[1] - self.start[1]
        if self.mode == GRAB:
            if typed is not None:
                a = self._axis_vec() if self.axis is not None else np.array([1.0, 0.0, 0.0])
                return translation(a * typed)
            d = (v.right * dx - v.up * dy) * v.world_per_px
            if self.axis is not None:
                a = self._axis_vec()
                # the mouse motion along the axis's screen direction
                sa = np.array([a @ v.right, -(a @ v.up)])
                L = float(np.hypot(*sa))
                if L < 1e-6:
                    return np.eye(4)
                t = (dx * sa[0] + dy * sa[1]) / (L * L) * v.world_per_px
                d = a * t
            return translation(d)
        if self.mode == ROTATE:
            axis = self._axis_vec() if self.axis is not None else v.back
            if typed is not None:
                ang = math.radians(typed)
            else:
                cx, cy = v.pivot_px
                a0 = math.atan2(self.start[1] - cy, self.start[0] - cx)
                a1 = math.atan2(self.mouse[1] - cy, self.mouse[0] - cx)
                # y is down: a growing atan2 is a clockwise sweep on screen, which is a
                # negative (right-handed) rotation about the axis pointing at the viewer
                ang = -(a1 - a0)
                if float(axis @ v.back) < 0:
                    ang = -ang
            return rotation(axis, ang, self.pivot)
        if self.mode == SCALE:
            if typed is not None:
                f = typed
            else:
                cx, cy = v.pivot_px
                r0 = math.hypot(self.start[0] - cx, self.start[1] - cy)
                r1 = math.hypot(self.mouse[0] - cx, self.mouse[1] - cy)
                f = r1 / max(r0, 1.0)
            f = max(f, 1e-3) if f >= 0 else min(f, -1e-3)
            fac = np.ones(3)
            if self.axis is None:
                fac[:] = f
            else:
                fac[self.axis] = f
            return scaling(fac, self.pivot)
        raise ValueError(self.mode)

    def describe(self) -> str:
        name = {GRAB: "Grab", ROTATE: "Rotate", SCALE: "Scale"}[self.mode]
        prep = "about" if self.mode == ROTATE else "along"
        ax = f" {prep} {AXIS_NAMES[self.axis]}" if self.axis is not None else ""
        val = f"  value: {self.typed}" if self.typed else ""
        return f"{name}{ax}{val}   (Enter/click: apply, Esc/right click: cancel)"


# ----------------------------------------------------------------- jobs
@dataclass
class Job:
    kind: str
    future: Future
    key: object = None
    stage: str = ""
    fraction: float = 0.0
    started: float = field(default_factory=time.perf_counter)
    cancel: threading.Event = field(default_factory=threading.Event)


class Session:
    """Document + selection + fitting + manipulation + history.

    Args:
        cloud: the loaded :class:`SplatCloud`.
        method, tol, max_centers: solver settings (also written to exported scripts).
        fit_sync: run fits on the calling thread (tests).
    """

    def __init__(self, cloud, *, method: str = "auto", tol: float = IQR_DEFAULT_TOL,
                 max_centers: int | None = None, fit_sync: bool = False, on_change=None):
        self.method, self.tol, self.max_centers = method, tol, max_centers
        self.fit_sync = fit_sync
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="splatedit-fit")
        self.on_change = on_change or (lambda: None)
        self.cloud = cloud
        self.selection = Selection(cloud.n)
        self.edits: tuple = ()
        self.history = History()
        self.history.reset(self._snapshot("open"))
        self.basis = None
        self.basis_key = None
        self.fit_job: Job | None = None
        self.fit_error: str | None = None
        self.manip: Manipulation | None = None
        self.brush_target = SUPPORT
        self.version = 0          # bumps whenever cloud or selection changes
        self.last_commit_seconds = 0.0

    # ---------------------------------------------------------- snapshots
    def _snapshot(self, label: str) -> Snapshot:
        return Snapshot.make(self.cloud, self.selection.support, self.selection.handle,
                             self.edits, label)

    def _restore(self, snap: Snapshot) -> None:
        self.cloud = snap.cloud
        s, h = snap.masks()
        self.selection = Selection(len(s), s, h)
        self.edits = snap.edits
        self.manip = None
        self.version += 1
        self.request_fit()
        self.on_change()

    def push(self, label: str) -> None:
        """Record the current state (after a stroke, clear or commit)."""
        self.history.push(self._snapshot(label))
        self.version += 1
        self.request_fit()
        self.on_change()

    def undo(self) -> bool:
        if self.manip is not None:
            self.cancel()
            return True
        snap = self.history.undo()
        if snap is None:
            return False
        self._restore(snap)
        return True

    def redo(self) -> bool:
        if self.manip is not None:
            return False
        snap = self.history.redo()
        if snap is None:
            return False
        self._restore(snap)
        return True

    @property
    def dirty(self) -> bool:
        return self.history.geometry_dirty

    # ------------------------------------------------------------ selection
    def paint(self, indices, erase: bool = False) -> bool:
        """Paint the current brush target (no history entry: call
        :meth:`end_stroke` when the stroke ends)."""
        if self.manip is not None:
            return False
        changed = self.selection.paint(indices, self.brush_target, erase)
        if changed:
            self.version += 1
        return changed

    def end_stroke(self, changed: bool) -> None:
        if changed:
            self.push(f"paint {self.brush_target}")

    def clear(self, target: str | None = None) -> None:
        if self.manip is None and self.selection.clear(target):
            self.push("clear")

    def set_selection(self, support, handle, label: str = "select") -> None:
        self.selection = Selection(self.cloud.n, support, handle)
        self.push(label)

    # --------------------------------------------------------------- fitting
    def selection_key(self):
        return (id(self.cloud),) + self.selection.key()

    def request_fit(self) -> None:
        """Start (or restart) a background fit when the handle is not empty."""
        key = self.selection_key()
        if self.basis is not None and self.basis_key == key:
            return
        if self.fit_job is not None:
            if self.fit_job.key == key:
                return
            self.fit_job.cancel.set()
            self.fit_job = None
        self.basis = None
        self.basis_key = None
        self.fit_error = None
        if not self.selection.handle.any():
            return
        cloud = self.cloud
        support = self.selection.support.copy()
        handle = self.selection.handle.copy()
        job = Job("fit", Future(), key=key, stage="fitting")

        def progress(stage, fraction):
            if job.cancel.is_set():
                raise Cancelled()
            job.stage, job.fraction = stage, fraction

        def work():
            from splatedit.deform.basis import DeformationBasis
            return DeformationBasis.fit(cloud, support, [handle], method=self.method, tol=self.tol,
                                        max_centers=self.max_centers, progress=progress)

        if self.fit_sync:
            try:
                job.future.set_result(work())
            except BaseException as exc:  # noqa: BLE001 - reported via poll
                job.future.set_exception(exc)
        else:
            job.future = self._pool.submit(work)
            job.future.add_done_callback(lambda f: self.on_change())
        self.fit_job = job

    def poll(self) -> bool:
        """Collect a finished fit; True when the state changed."""
        job = self.fit_job
        if job is None or not job.future.done():
            return False
        self.fit_job = None
        if job.key != self.selection_key():
            self.request_fit()
            return True
        try:
            self.basis = job.future.result()
            self.basis_key = job.key
        except Cancelled:
            return False
        except SplatEditError as exc:
            self.fit_error = str(exc)
        except Exception as exc:  # noqa: BLE001 - a bug, but keep the editor alive
            self.fit_error = f"internal error while fitting: {exc!r}"
            traceback.print_exc()
        return True

    def wait_fit(self, timeout: float = 120.0) -> bool:
        """Block until the fit finishes (tests and scripted use)."""
        t0 = time.perf_counter()
        while self.fit_job is not None and time.perf_counter() - t0 < timeout:
            try:
                self.fit_job.future.result(timeout=0.05)
            except Exception:  # noqa: BLE001
                pass
            self.poll()
        return self.basis is not None

    @property
    def fitting(self) -> bool:
        return self.fit_job is not None

    @property
    def state(self) -> str:
        if self.manip is not None:
            return "manipulate"
        if self.fit_job is not None:
            return "fitting"
        if self.basis is not None:
            return "ready"
        if self.fit_error:
            return "error"
        return "select"

    # ---------------------------------------------------------- manipulation
    def handle_centroid(self) -> np.ndarray:
        return self.cloud.positions[self.selection.handle].mean(axis=0)

    def begin(self, mode: str, view: ViewInfo, mouse: tuple[float, float]) -> bool:
        """Start G/R/S (needs a fitted basis)."""
        if self.basis is None or self.manip is not None:
            return False
        self.manip = Manipulation(mode, self.handle_centroid(), view, mouse)
        return True

    def current_matrix(self) -> np.ndarray:
        return np.eye(4) if self.manip is None else self.manip.matrix()

    def current_dc(self) -> np.ndarray | None:
        """dC of the current manipulation (None when there is no basis)."""
        if self.basis is None:
            return None
        return self.basis.displacement([self.current_matrix()])

    def cancel(self) -> None:
        self.manip = None
        self.on_change()

    def commit(self) -> bool:
        """Apply the current manipulation: the deformed cloud becomes the new
        base, the edit is recorded, the selection is kept."""
        from splatedit.script import Edit, Matrix
        from splatedit.select.regions import Indices
        if self.manip is None or self.basis is None:
            return False
        m = self.manip.matrix()
        self.manip = None
        if np.allclose(m, np.eye(4), atol=0, rtol=0):
            self.on_change()
            return False
        t0 = time.perf_counter()
        dc = self.basis.displacement([m])
        # the same arrays as ``splatedit deform`` (basis.apply); only the moved
        # (support) splats are re-validated, the others are bitwise copies
        new = self.basis.apply(self.cloud, dc)
        new.subset(self.basis.indices)      # raises InputError on a degenerate splat
        self.last_commit_seconds = time.perf_counter() - t0
        sup = self.selection.support
        edit = Edit(Indices(tuple(int(i) for i in np.flatnonzero(sup))),
                    (Indices(tuple(int(i) for i in np.flatnonzero(self.selection.handle))),),
                    (Matrix(tuple(tuple(float(x) for x in row) for row in m)),))
        self.cloud = new
        self.edits = self.edits + (edit,)
        self.basis = None
        self.basis_key = None
        self.push("edit")
        return True

    # ---------------------------------------------------------------- export
    def edit_script(self):
        from splatedit.script import EditScript, SolverSettings
        return EditScript(tuple(self.edits), SolverSettings(self.method, self.tol, self.max_centers))

    def stats(self) -> dict:
        s = {"state": self.state, "support": self.selection.counts[0],
             "handle": self.selection.counts[1], "edits": len(self.edits)}
        if self.basis is not None:
            st = self.basis.stats if isinstance(self.basis.stats, dict) else vars(self.basis.stats)
            s.update(centers=st.get("n_centers"), constraints=st.get("n_constraints"),
                     residual=st.get("residual"), method=st.get("method"),
                     fit_seconds=st.get("fit_seconds"), basis_seconds=st.get("basis_seconds"))
        if self.fit_job is not None:
            s.update(stage=self.fit_job.stage, fraction=self.fit_job.fraction,
                     elapsed=time.perf_counter() - self.fit_job.started)
        if self.fit_error:
            s["error"] = self.fit_error
        return s

    def close(self) -> None:
        if self.fit_job is not None:
            self.fit_job.cancel.set()
        self._pool.shutdown(wait=False, cancel_futures=True)

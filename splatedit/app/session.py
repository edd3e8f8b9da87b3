"""The edit session state machine (no window, no GPU: unit-testable).

States::

    SELECT --(handle painted)--> fit runs in a worker thread (FITTING)
    FITTING --(done)--> READY (basis available; the handle can be moved)
    READY --G/R/S or drag--> MANIPULATE (matrix changes every mouse move)
    MANIPULATE --Enter / release--> commit: the deformed cloud becomes the
        new base (the selection is kept, a new fit starts for the next edit)
    MANIPULATE --Esc / right click--> cancel (back to READY)

The *rig* of an edit (paper Sect. 3 and 6 end): one support, one or more
disjoint handles (one active, moved by the manipulator) and optionally one
non-rigid control curve (2..16 picked points, a centripetal Catmull-Rom
curve through them, :class:`~splatedit.deform.curves.ControlCurve`).  One basis is
fitted for all of them at once: 4 columns per non-empty handle, k + 1 for
the curve, at most ``RENDER_MAX_BASIS_COLUMNS`` (16) in total.  The *pose*
is a pending matrix per handle plus a pending displacement per picked curve
point; every frame ``dC = basis.displacement(pose)`` for all columns.

When the rig is a single handle without curve, ending a manipulation
commits the edit at once (as before).  Otherwise ending a manipulation only
stores it in the pose (the other handles keep theirs) and :meth:`Session.
commit` (Enter) applies the whole pose as one edit; :meth:`Session.
reset_pose` (Esc) discards it.  A commit consumes the curve (its points are
cleared; undo brings them back) and keeps support and handles.

Every user action that changes the document (a stroke, a clear, a commit)
pushes a :class:`~splatedit.app.history.Snapshot`; undo/redo restore them
(and restart the fit for the restored selection).  Committed edits are
recorded as script edits (``indices`` support + ``indices`` handles +
``matrix`` transforms + ``curves`` with ``points`` and ``move``) and :meth:`Session.edit_script` returns an
:class:`~splatedit.script.EditScript` with the session's solver settings, so
``splatedit deform INPUT --edit script.json`` reproduces the saved cloud.
"""

from __future__ import annotations

import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from splatedit.app import revision
from splatedit.select.selection import HANDLE, SUPPORT, Selection
from splatedit.app.history import History, Snapshot
from splatedit.app.jobs import Cancelled, Job
from splatedit.deform.transform import compose, rotate, scale, translate
from splatedit.errors import SplatEditError
from splatedit.tolerances import (EDITOR_AXIS_MIN_SCREEN_LEN, EDITOR_MIN_SCALE_FACTOR, IQR_DEFAULT_TOL,
                                  RENDER_MAX_BASIS_COLUMNS)

GRAB, ROTATE, SCALE = "grab", "rotate", "scale"
#: basis columns per rigid handle
HANDLE_COLUMNS = 4
#: at most this many picked points per control curve
MAX_CURVE_POINTS = 16
AXIS_NAMES = "XYZ"


def _axis_scaling(axis: int, factor: float, center) -> np.ndarray:
    """Scale by ``factor`` (> 0) along world axis ``axis`` about ``center``."""
    s = np.eye(4)
    s[axis, axis] = factor
    c = np.asarray(center, float)
    return compose(translate(-c), s, translate(c))


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

    def problem(self) -> str | None:
        """Why the typed value cannot be applied (None when it can): a scale
        factor must be > 0 (a negative one mirrors the handle and turns its
        normals inside out, 0 flattens it)."""
        v = self.typed_value()
        if v is not None and not math.isfinite(v):
            return "the typed value is too large"
        if self.mode == SCALE and v is not None and not v > 0:
            return f"the scale factor must be > 0, got {self.typed}"
        return None

    def _axis_vec(self) -> np.ndarray:
        a = np.zeros(3)
        a[self.axis] = 1.0
        return a

    def _translation(self, typed) -> np.ndarray:
        """(3,) grab displacement, model units."""
        v = self.view
        if typed is not None:
            a = self._axis_vec() if self.axis is not None else np.array([1.0, 0.0, 0.0])
            return a * typed
        dx = self.mouse[0] - self.start[0]
        dy = self.mouse[1] - self.start[1]
        if self.axis is None:
            return (v.right * dx - v.up * dy) * v.world_per_px
        a = self._axis_vec()
        # the mouse motion along the axis's screen direction
        sa = np.array([a @ v.right, -(a @ v.up)])
        L = float(np.hypot(*sa))
        if L < EDITOR_AXIS_MIN_SCREEN_LEN:
            return np.zeros(3)
        return a * ((dx * sa[0] + dy * sa[1]) / (L * L) * v.world_per_px)

    def _angle_deg(self, typed) -> float:
        """Rotation angle (degrees, right-handed about :meth:`_rot_axis`)."""
        if typed is not None:
            return float(typed)
        v = self.view
        cx, cy = v.pivot_px
        a0 = math.atan2(self.start[1] - cy, self.start[0] - cx)
        a1 = math.atan2(self.mouse[1] - cy, self.mouse[0] - cx)
        # y is down: a growing atan2 is a clockwise sweep on screen, which is a
        # negative (right-handed) rotation about the axis pointing at the viewer
        ang = -(a1 - a0)
        if float(self._rot_axis() @ v.back) < 0:
            ang = -ang
        ang = (ang + math.pi) % (2 * math.pi) - math.pi      # the same rotation, in (-180, 180]
        return math.degrees(ang)

    def _rot_axis(self) -> np.ndarray:
        return self._axis_vec() if self.axis is not None else self.view.back

    def _factor(self, typed) -> float:
        if typed is not None:
            f = typed
        else:
            cx, cy = self.view.pivot_px
            r0 = math.hypot(self.start[0] - cx, self.start[1] - cy)
            r1 = math.hypot(self.mouse[0] - cx, self.mouse[1] - cy)
            f = r1 / max(r0, 1.0)
        return max(f, EDITOR_MIN_SCALE_FACTOR)

    def _typed_ok(self):
        return self.typed_value() if self.problem() is None else None

    def matrix(self) -> np.ndarray:
        """The manipulation's (4, 4) matrix; a typed value that cannot be
        applied (:meth:`problem`, shown by :meth:`describe`) is ignored: the
        mouse's value is used meanwhile."""
        typed = self._typed_ok()
        if self.mode == GRAB:
            return translate(self._translation(typed))
        if self.mode == ROTATE:
            return rotate(self._rot_axis(), self._angle_deg(typed), self.pivot)
        if self.mode == SCALE:
            f = self._factor(typed)
            if self.axis is None:
                return scale(f, self.pivot)
            return _axis_scaling(self.axis, f, self.pivot)
        raise ValueError(self.mode)

    def readout(self) -> str:
        """The live value of the move, as the overlay shows it next to the
        cursor: grab distance (model units) and its X/Y/Z components, rotate
        angle (degrees), scale factor; "typed" when it comes from the keys."""
        typed = self._typed_ok()
        src = "  (typed)" if typed is not None else ""
        ax = f" {AXIS_NAMES[self.axis]}" if self.axis is not None else ""
        if self.mode == GRAB:
            d = self._translation(typed)
            return (f"distance{ax} {float(np.linalg.norm(d)):.4g}   "
                    f"({d[0]:+.3g}, {d[1]:+.3g}, {d[2]:+.3g}){src}")
        if self.mode == ROTATE:
            return f"angle{ax} {self._angle_deg(typed):+.1f} deg{src}"
        return f"factor{ax} {self._factor(typed):.3f}x{src}"

    def describe(self) -> str:
        name = {GRAB: "Grab", ROTATE: "Rotate", SCALE: "Scale"}[self.mode]
        prep = "about" if self.mode == ROTATE else "along"
        ax = f" {prep} {AXIS_NAMES[self.axis]}" if self.axis is not None else ""
        val = f"  value: {self.typed}" if self.typed else ""
        bad = self.problem()
        if bad:
            val += f"  ({bad})"
        return f"{name}{ax}{val}   (Enter/click: apply, Esc/right click: cancel)"


def columns_needed(n_handles: int, n_curve_points: int) -> int:
    """Basis columns of a rig: 4 per handle, k + 1 for a curve of k + 1 >= 2 points."""
    return HANDLE_COLUMNS * n_handles + (n_curve_points if n_curve_points >= 2 else 0)


def _matrix_tuple(m) -> tuple:
    return tuple(tuple(float(x) for x in row) for row in np.asarray(m, float))


class Session:
    """Document + selection (support, handles, curve) + fitting + pose +
    manipulation + history.

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
        self.pose: list[np.ndarray] = [np.eye(4)]      # pending matrix per handle
        self.curve_points: list[np.ndarray] = []       # picked points (3,) of the control curve
        self.curve_moves = np.zeros((0, 3))            # pending displacement per picked point
        self.curve_mode = False                        # the editor's curve tool is on
        self.edits: tuple = ()
        self.history = History()
        self.history.reset(self._snapshot("open"))
        self.basis = None
        self.basis_key = None
        self.basis_groups = None      # (fitted handle indices, ControlCurve or None) of the basis
        self.fit_job: Job | None = None
        self.fit_error: str | None = None
        self.manip: Manipulation | None = None
        self.manip_target = None      # ("handle", i) or ("curve", j)
        self.brush_target = SUPPORT
        self.version = 0          # bumps whenever cloud or selection changes
        self.last_commit_seconds = 0.0
        self._curve_cache = (None, None)

    # ---------------------------------------------------------- snapshots
    def _rig(self) -> tuple:
        return (tuple(tuple(float(x) for x in p) for p in self.curve_points),
                tuple(tuple(float(x) for x in d) for d in self.curve_moves),
                tuple(_matrix_tuple(m) for m in self.pose))

    def _snapshot(self, label: str) -> Snapshot:
        return Snapshot.make(self.cloud, self.selection.support, self.selection.handles, self.edits,
                             label, active=self.selection.active, rig=self._rig())

    def _restore(self, snap: Snapshot) -> None:
        self.cloud = snap.cloud
        s, _ = snap.masks()
        self.selection = Selection(len(s), s, handles=snap.handle_masks(), active=snap.active)
        pts, moves, pose = snap.rig if snap.rig else ((), (), ())
        self.curve_points = [np.array(p, float) for p in pts]
        self.curve_moves = np.array(moves, float).reshape(-1, 3)
        self.pose = [np.array(m, float) for m in pose]
        self._sync_pose()
        self.edits = snap.edits
        self.manip = None
        self.manip_target = None
        self.version += 1
        self.request_fit()
        self.on_change()

    def _sync_pose(self) -> None:
        n = len(self.selection.handles)
        self.pose = (self.pose + [np.eye(4) for _ in range(n)])[:n]

    def push(self, label: str) -> None:
        """Record the current state (after a stroke, clear, pose change or commit)."""
        self._sync_pose()
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
            self.pose = [np.eye(4)]
            self.push("clear")

    def set_selection(self, support, handle, label: str = "select") -> None:
        handles = handle if isinstance(handle, (list, tuple)) else [handle]
        self.selection = Selection(self.cloud.n, support, handles=handles)
        self.pose = [np.eye(4)]
        self.push(label)

    # -------------------------------------------------------------- handles
    def _check_columns(self, n_handles: int, n_points: int, what: str) -> None:
        k = columns_needed(n_handles, n_points)
        if k > RENDER_MAX_BASIS_COLUMNS:
            raise SplatEditError(
                f"cannot {what}: the basis would need {k} columns (4 per handle + 1 per curve point "
                f"from 2 points on), at most {RENDER_MAX_BASIS_COLUMNS} are supported")

    def _n_handles_planned(self) -> int:
        """Handles that take basis columns (all but a lone empty one)."""
        hs = self.selection.handles
        return len(hs) if (len(hs) > 1 or hs[0].any()) else 0

    def add_handle(self) -> bool:
        """Start a new handle (active; the brush then paints it).  An empty
        active handle is reused.  Raises SplatEditError over 16 columns."""
        if self.manip is not None:
            return False
        self.brush_target = HANDLE
        if not self.selection.handle.any():
            return False
        self._check_columns(len(self.selection.handles) + 1, len(self.curve_points), "add a handle")
        self.selection.add_handle()
        self.push("new handle")
        return True

    def remove_handle(self) -> bool:
        """Remove the active handle (and its pending transform)."""
        if self.manip is not None:
            return False
        i = self.selection.active
        several = len(self.selection.handles) > 1
        if not self.selection.remove_handle(i):
            return False
        if several:
            del self.pose[i]
        else:
            self.pose = [np.eye(4)]
        self.push("remove handle")
        return True

    def select_handle(self, i: int) -> bool:
        """Make handle ``i`` (modulo the count) the active one (not an undo step)."""
        if self.manip is not None or not self.selection.select_handle(i):
            return False
        self.version += 1
        self.on_change()
        return True

    def cycle_handle(self, step: int = 1) -> bool:
        return self.select_handle(self.selection.active + step)

    # ---------------------------------------------------------------- curve
    def curve(self):
        """The :class:`ControlCurve` through the picked points (None below 2)."""
        if len(self.curve_points) < 2:
            return None
        key = tuple(p.tobytes() for p in self.curve_points)
        if self._curve_cache[0] != key:
            from splatedit.deform.curves import ControlCurve
            self._curve_cache = (key, ControlCurve.through(np.array(self.curve_points, dtype=np.float64)))
        return self._curve_cache[1]

    def add_curve_point(self, point) -> bool:
        """Append a picked point (2..16 per curve; consecutive ones distinct)."""
        if self.manip is not None:
            return False
        p = np.array(point, dtype=np.float64).reshape(3)
        if len(self.curve_points) >= MAX_CURVE_POINTS:
            raise SplatEditError(f"a curve has at most {MAX_CURVE_POINTS} points")
        self._check_columns(self._n_handles_planned(), len(self.curve_points) + 1, "add a curve point")
        if self.curve_points:
            from splatedit.deform.curves import first_coincident_point
            # the same check (consecutive points distinct) as building the curve
            if first_coincident_point(np.array(self.curve_points + [p])) is not None:
                raise SplatEditError("this point is the curve's last point: pick another one")
        self.curve_points.append(p)
        self.curve_moves = np.vstack([self.curve_moves, np.zeros((1, 3))])
        self.push("curve point")
        return True

    def remove_curve_point(self) -> bool:
        """Remove the last picked point."""
        if self.manip is not None or not self.curve_points:
            return False
        self.curve_points.pop()
        self.curve_moves = self.curve_moves[:-1].copy()
        self.push("remove curve point")
        return True

    def clear_curve(self) -> bool:
        if self.manip is not None or not self.curve_points:
            return False
        self.curve_points = []
        self.curve_moves = np.zeros((0, 3))
        self.push("clear curve")
        return True

    def curve_point_positions(self, live: bool = True) -> np.ndarray:
        """(k + 1, 3) current (moved) picked points."""
        if not self.curve_points:
            return np.zeros((0, 3))
        return np.array(self.curve_points) + self.live_curve_moves(live)

    def curve_polyline(self, count: int = 160, live: bool = True) -> np.ndarray | None:
        """(>= count, 3) points of the moved curve ``c'(t) = c(t) + W(t) dq``
        for drawing: exactly the targets the fitted deformation gives the
        curve's samples (through every moved picked point; None below 2
        points)."""
        c = self.curve()
        if c is None:
            return None
        t = np.union1d(np.linspace(0.0, 1.0, count), c.params)
        return c.evaluate(t, c.points + self.live_curve_moves(live))

    # --------------------------------------------------------------- fitting
    def selection_key(self):
        curve = tuple(p.tobytes() for p in self.curve_points) if len(self.curve_points) >= 2 else ()
        return (revision.of(self.cloud),) + self.selection.key() + (curve,)

    def request_fit(self) -> None:
        """Start (or restart) a background fit of all non-empty handles and
        the curve (when it has at least 2 points)."""
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
        self.basis_groups = None
        self.fit_error = None
        hidx = self.selection.nonempty()
        curve = self.curve()
        if not hidx and curve is None:
            return
        if not self.selection.support.any():
            self.fit_error = "paint a support region first (1)"
            return
        k = columns_needed(len(hidx), len(self.curve_points))
        if k > RENDER_MAX_BASIS_COLUMNS:
            self.fit_error = (f"{k} basis columns needed (4 per handle + 1 per curve point), at most "
                              f"{RENDER_MAX_BASIS_COLUMNS}: remove a handle or curve points")
            return
        cloud = self.cloud
        support = self.selection.support.copy()
        handles = [self.selection.handles[k].copy() for k in hidx]
        curves = [curve] if curve is not None else []
        def work(progress):
            from splatedit.deform.basis import DeformationBasis
            return DeformationBasis.fit(cloud, support, handles, curves=curves, method=self.method,
                                        tol=self.tol, max_centers=self.max_centers, progress=progress,
                                        fill_holes=False)  # closed visibly after each stroke

        # fits run one at a time on the session's pool (a cancelled one ends at its
        # next progress report); fit_sync runs it here
        job = Job("fitting", work, None if self.fit_sync else self.on_change, key=key,
                  executor=self._pool, sync=self.fit_sync)
        job.groups = (tuple(hidx), curve)
        self.fit_job = job

    def poll(self) -> bool:
        """Collect a finished fit; True when the state changed."""
        job = self.fit_job
        if job is None or not job.done:
            return False
        self.fit_job = None
        key, groups = job.key, job.groups
        if key != self.selection_key():
            self.request_fit()
            return True
        exc = job.error
        if exc is None:
            self.basis = job.result
            self.basis_key = key
            self.basis_groups = groups
        elif isinstance(exc, Cancelled):
            return False
        elif isinstance(exc, SplatEditError):
            self.fit_error = str(exc)
        else:   # a bug (its traceback is printed by the job), but keep the editor alive
            self.fit_error = f"internal error while fitting: {exc!r}"
        return True

    def wait_fit(self, timeout: float = 120.0) -> bool:
        """Block until the fit finishes (tests and scripted use)."""
        t0 = time.perf_counter()
        while self.fit_job is not None and time.perf_counter() - t0 < timeout:
            self.fit_job.wait(0.05)
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

    # ------------------------------------------------------------------ pose
    @property
    def single_rig(self) -> bool:
        """One handle and no curve: ending a manipulation commits at once."""
        return len(self.selection.handles) == 1 and not self.curve_points

    @property
    def pose_pending(self) -> bool:
        """Some handle or curve point has a pending (uncommitted) move."""
        return (any(not np.array_equal(m, np.eye(4)) for m in self.pose)
                or bool(self.curve_moves.any()))

    def handle_matrix(self, k: int, live: bool = True) -> np.ndarray:
        """Pending matrix of handle ``k`` (with the running manipulation when ``live``)."""
        m = self.pose[k] if k < len(self.pose) else np.eye(4)
        if live and self.manip is not None and self.manip_target == ("handle", k):
            m = self.manip.matrix() @ m
        return m

    def live_curve_moves(self, live: bool = True) -> np.ndarray:
        mv = self.curve_moves.copy()
        if live and self.manip is not None and self.manip_target and self.manip_target[0] == "curve":
            j = self.manip_target[1]
            p = self.curve_points[j] + mv[j]
            m = self.manip.matrix()
            mv[j] = m[:3, :3] @ p + m[:3, 3] - self.curve_points[j]
        return mv

    def inputs(self, live: bool = True) -> list:
        """Per-group inputs of ``basis.displacement`` (fitted handles, then the curve)."""
        hidx, curve = self.basis_groups
        out = [self.handle_matrix(k, live) for k in hidx]
        if curve is not None:
            out.append(self.live_curve_moves(live))  # the curve's controls are its picked points
        return out

    def reset_pose(self) -> bool:
        """Discard the pending transforms and curve moves (an undo step)."""
        if self.manip is not None:
            self.cancel()
        if not self.pose_pending:
            return False
        self.pose = [np.eye(4) for _ in self.selection.handles]
        self.curve_moves = np.zeros_like(self.curve_moves)
        self.push("reset pose")
        return True

    # ---------------------------------------------------------- manipulation
    def handle_centroid(self, k: int | None = None) -> np.ndarray:
        """Centroid of handle ``k`` (default: the active one) moved by its pending matrix."""
        k = self.selection.active if k is None else k
        c = self.cloud.positions[self.selection.handles[k]].mean(axis=0)
        m = self.pose[k] if k < len(self.pose) else np.eye(4)
        return m[:3, :3] @ c + m[:3, 3]

    def active_fitted(self) -> bool:
        """The active handle is part of the fitted basis."""
        return self.basis is not None and self.selection.active in self.basis_groups[0]

    def begin(self, mode: str, view: ViewInfo, mouse: tuple[float, float]) -> bool:
        """Start G/R/S of the active handle (needs a basis that includes it)."""
        if self.manip is not None or not self.active_fitted():
            return False
        self.manip = Manipulation(mode, self.handle_centroid(), view, mouse)
        self.manip_target = ("handle", self.selection.active)
        return True

    def begin_curve_point(self, j: int, view: ViewInfo, mouse: tuple[float, float]) -> bool:
        """Start dragging picked curve point ``j`` (needs a basis with the curve)."""
        if self.manip is not None or self.basis is None or self.basis_groups[1] is None:
            return False
        if not 0 <= j < len(self.curve_points):
            return False
        self.manip = Manipulation(GRAB, self.curve_points[j] + self.curve_moves[j], view, mouse)
        self.manip_target = ("curve", int(j))
        return True

    def current_matrix(self) -> np.ndarray:
        return np.eye(4) if self.manip is None else self.manip.matrix()

    def current_dc(self) -> np.ndarray | None:
        """dC of the whole pose, live manipulation included (None without basis)."""
        if self.basis is None:
            return None
        return self.basis.displacement(self.inputs())

    def distortion(self):
        """:class:`~splatedit.deform.distortion.DistortionStats` of the support
        for the current pose (live manipulation included), or None without a
        basis, when nothing is moved, or before the first figures are ready.

        Computed off the UI thread (a background job per pose, one at a time;
        ``on_change`` is called when it is done), so a drag never waits for it:
        the figures shown may be those of the pose one job earlier (a
        DistortionProbe is built once per (basis, cloud); then about 5 ms per
        100k support splats, see docs/PERFORMANCE.md).  ``fit_sync`` sessions
        compute synchronously (tests)."""
        dc = self.current_dc()
        if dc is None or not dc.any():
            return None
        from splatedit.deform.distortion import DistortionProbe
        src = (self.basis, self.cloud)
        d = getattr(self, "_dist", None)
        if d is None or d["src"][0] is not src[0] or d["src"][1] is not src[1]:
            d = self._dist = {"src": src, "probe": None, "job": None, "result": None}
        job = d["job"]
        if job is not None and job.done:
            d["job"] = None
            if job.error is None:
                d["result"] = job.result
        key = dc.tobytes()
        if d["job"] is None and (d["result"] is None or d["result"][0] != key):
            basis, cloud = src

            def work(progress):
                if d["probe"] is None:
                    d["probe"] = DistortionProbe(basis, cloud)
                return key, d["probe"].stats(dc)
            d["job"] = Job("distortion", work, self.on_change, sync=self.fit_sync)
            if d["job"].done:
                return self.distortion()
        return None if d["result"] is None else d["result"][1]

    def cancel(self) -> None:
        self.manip = None
        self.manip_target = None
        self.on_change()

    def _check_manip(self) -> None:
        """Raise SplatEditError (state unchanged) when the running manipulation's
        typed value cannot be applied (e.g. a scale factor <= 0)."""
        bad = self.manip.problem() if self.manip is not None else None
        if bad:
            raise SplatEditError(bad)

    def _bake(self) -> None:
        """Store the running manipulation in the pose."""
        t = self.manip_target
        if t[0] == "handle":
            self.pose[t[1]] = self.handle_matrix(t[1])
        else:
            self.curve_moves = self.live_curve_moves()
        self.manip = None
        self.manip_target = None

    def finish(self) -> str:
        """End the running manipulation: commit at once for a single-handle
        rig ("commit", or "" when nothing moved); else keep it in the pose
        ("pose") for a later :meth:`commit`."""
        if self.manip is None:
            return ""
        self._check_manip()
        if self.single_rig:
            return "commit" if self.commit() else ""
        moved = not np.array_equal(self.manip.matrix(), np.eye(4))
        what = "move handle" if self.manip_target[0] == "handle" else "move curve point"
        self._bake()
        if moved:
            self.push(what)
        else:
            self.on_change()
        return "pose" if moved else ""

    def commit(self) -> bool:
        """Apply the pose (running manipulation included) as one edit: the
        deformed cloud becomes the new base, the edit is recorded, support and
        handles are kept, the curve is consumed.  Raises InputError (state
        unchanged) when a splat degenerates."""
        from splatedit.script import Curve, Edit, Matrix
        from splatedit.select.regions import Indices
        if self.basis is None:
            return False
        self._check_manip()
        inputs = self.inputs(live=True)
        moves = self.live_curve_moves(live=True)
        hidx, curve = self.basis_groups
        mats = inputs[:len(hidx)]
        if all(np.array_equal(m, np.eye(4)) for m in mats) and not (curve is not None and moves.any()):
            self.manip = None
            self.manip_target = None
            self.on_change()
            return False
        t0 = time.perf_counter()
        dc = self.basis.displacement(inputs)
        # the same arrays and the same checks as ``splatedit deform`` and as reading the
        # saved file: the whole cloud is validated (SplatCloud.validate: the minimum axis
        # length is relative to the *whole* cloud's diagonal, which the edit may change)
        new = self.basis.commit(self.cloud, dc)     # raises InputError on a degenerate splat
        self.last_commit_seconds = time.perf_counter() - t0
        sel = self.selection
        idx = lambda m: Indices(tuple(int(i) for i in np.flatnonzero(m)))  # noqa: E731
        curves = ()
        if curve is not None:
            curves = (Curve(tuple(tuple(float(x) for x in p) for p in self.curve_points),
                            tuple(tuple(float(x) for x in d) for d in moves), None),)
        edit = Edit(idx(sel.support), tuple(idx(sel.handles[k]) for k in hidx),
                    tuple(Matrix(_matrix_tuple(m)) for m in mats), "$", curves,
                    fill_holes=False)  # the editor's closed selection, replayed as is
        self.manip = None
        self.manip_target = None
        self.cloud = new
        self.edits = self.edits + (edit,)
        self.basis = None
        self.basis_key = None
        self.basis_groups = None
        self.pose = [np.eye(4) for _ in sel.handles]
        self.curve_points = []
        self.curve_moves = np.zeros((0, 3))
        self.push("edit")
        return True

    # ---------------------------------------------------------------- export
    def edit_script(self):
        from splatedit.script import EditScript, SolverSettings
        return EditScript(tuple(self.edits), SolverSettings(self.method, self.tol, self.max_centers))

    def stats(self) -> dict:
        sel = self.selection
        s = {"state": self.state, "support": sel.counts[0], "handle": sel.counts[1],
             "edits": len(self.edits), "handles": len(sel.handles), "active_handle": sel.active,
             "handle_sizes": [int(h.sum()) for h in sel.handles], "curve_points": len(self.curve_points),
             "pose_pending": self.pose_pending,
             "columns": columns_needed(len(sel.nonempty()), len(self.curve_points))}
        if self.basis is not None:
            st = self.basis.stats if isinstance(self.basis.stats, dict) else vars(self.basis.stats)
            s.update(centers=st.get("n_centers"), constraints=st.get("n_constraints"),
                     residual=st.get("residual"), method=st.get("method"),
                     fit_seconds=st.get("fit_seconds"), basis_seconds=st.get("basis_seconds"),
                     columns=self.basis.n_columns)
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

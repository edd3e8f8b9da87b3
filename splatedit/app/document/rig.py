"""The rig of an edit session (paper Sect. 3 and 6 end) beyond the
selection masks: the pending pose of each handle, the control curve's picked
points and their pending moves, and whether the curve tool is on."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def matrix_tuple(m) -> tuple:
    """A (4, 4) matrix as a tuple of row tuples of floats (hashable, JSON-able)."""
    return tuple(tuple(float(x) for x in row) for row in np.asarray(m, float))


@dataclass
class Rig:
    """``pose``: one pending (4, 4) float64 matrix per handle;
    ``curve_points``: picked points, each (3,) float64 model units;
    ``curve_moves``: (k, 3) float64 pending displacement per picked point."""
    pose: list = field(default_factory=lambda: [np.eye(4)])
    curve_points: list = field(default_factory=list)
    curve_moves: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    curve_mode: bool = False
    _curve_cache: tuple = (None, None)

    # ---------------------------------------------------------- snapshots
    def as_tuple(self) -> tuple:
        """Hashable copy (for undo snapshots)."""
        return (tuple(tuple(float(x) for x in p) for p in self.curve_points),
                tuple(tuple(float(x) for x in d) for d in self.curve_moves),
                tuple(matrix_tuple(m) for m in self.pose))

    def restore(self, t: tuple | None) -> None:
        pts, moves, pose = t if t else ((), (), ())
        self.curve_points = [np.array(p, float) for p in pts]
        self.curve_moves = np.array(moves, float).reshape(-1, 3)
        self.pose = [np.array(m, float) for m in pose]

    def sync_pose(self, n_handles: int) -> None:
        """One pending matrix per handle (identity for new ones)."""
        self.pose = (self.pose + [np.eye(4) for _ in range(n_handles)])[:n_handles]

    def reset_pose(self, n_handles: int) -> None:
        self.pose = [np.eye(4) for _ in range(n_handles)]
        self.curve_moves = np.zeros_like(self.curve_moves)

    def clear_curve(self) -> None:
        self.curve_points = []
        self.curve_moves = np.zeros((0, 3))

    @property
    def pending(self) -> bool:
        """Some handle or curve point has a pending (uncommitted) move."""
        return any(not np.array_equal(m, np.eye(4)) for m in self.pose) or bool(self.curve_moves.any())

    # --------------------------------------------------------------- curve
    def curve(self):
        """The :class:`~splatedit.deform.curves.ControlCurve` through the
        picked points (None below 2; cached per point set)."""
        if len(self.curve_points) < 2:
            return None
        key = tuple(p.tobytes() for p in self.curve_points)
        if self._curve_cache[0] != key:
            from splatedit.deform.curves import ControlCurve
            self._curve_cache = (key, ControlCurve.through(np.array(self.curve_points, dtype=np.float64)))
        return self._curve_cache[1]

    def curve_key(self) -> tuple:
        """What the basis depends on of the curve (nothing below 2 points)."""
        return tuple(p.tobytes() for p in self.curve_points) if len(self.curve_points) >= 2 else ()

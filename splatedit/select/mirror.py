"""Mirror (X-symmetry) selection: the splat across a model's symmetry plane.

The plane is ``x[axis] = c`` with ``c`` the centre of the bounding box along
``axis`` (0 = X, the usual symmetry of a figure, an animal or a vehicle);
a splat's mirror is the splat nearest to its reflection, when that one is
within :data:`~splatedit.tolerances.MIRROR_MATCH_SPACINGS` median spacings
(a part with no counterpart has no mirror), and a splat whose own
reflection lands nearest to a selected splat is in the mirror image too (so
a region mirrors whole where the two sides are sampled differently).  Pure numpy/scipy.
"""

from __future__ import annotations

import numpy as np

from splatedit.tolerances import MIRROR_MATCH_SPACINGS

#: neighbours of each reflection looked at (the nearest, and candidates of the pull)
MIRROR_CANDIDATES = 4

AXES = "XYZ"


def plane_centre(positions: np.ndarray, axis: int = 0) -> float:
    """The symmetry plane's offset along ``axis``: the middle of the
    bounding box of ``positions`` (n, 3) on that axis (model units)."""
    p = np.asarray(positions, float)[:, axis]
    return 0.5 * float(p.min() + p.max())


def reflect(points: np.ndarray, axis: int, centre: float) -> np.ndarray:
    """(m, 3): ``points`` (m, 3) reflected across the plane x[axis] = centre."""
    q = np.array(points, float, copy=True).reshape(-1, 3)
    q[:, axis] = 2.0 * centre - q[:, axis]
    return q


def mirror_indices(positions: np.ndarray, idx, tree, spacing: float, axis: int = 0,
                   centre: float | None = None) -> np.ndarray:
    """Sorted unique indices of the mirror images of splats ``idx``.

    Args:
        positions: (n, 3) splat centres (model units).
        idx: indices of the splats to mirror.
        tree: a cKDTree of ``positions``.
        spacing: the median neighbour spacing (model units).
        axis: the plane's normal axis (0, 1, 2).
        centre: the plane's offset (None: :func:`plane_centre`).
    """
    idx = np.asarray(idx, np.int64).ravel()
    if not len(idx):
        return np.zeros(0, np.int64)
    pos = np.asarray(positions)
    c = plane_centre(pos, axis) if centre is None else float(centre)
    tol = MIRROR_MATCH_SPACINGS * max(float(spacing), 1e-300)
    # push: the splats nearest to each reflected one (the first column), and
    # near it (the others: candidates of the pull below)
    d, j = tree.query(reflect(pos[idx], axis, c), k=MIRROR_CANDIDATES, distance_upper_bound=tol, workers=-1)
    ok = np.isfinite(d)
    push = j[:, 0][ok[:, 0]].astype(np.int64)
    cand = np.setdiff1d(np.unique(j[ok].astype(np.int64)), push)    # the push's are in already
    # pull: a candidate whose own reflection lands nearest to a selected splat
    # (the nearest-sample map is many-to-one: push alone leaves holes where the
    # other side is sampled more densely)
    chosen = np.zeros(len(pos), bool)
    chosen[idx] = True
    if len(cand):
        d2, k2 = tree.query(reflect(pos[cand], axis, c), distance_upper_bound=tol, workers=-1)
        good = np.isfinite(d2)
        cand = cand[good][chosen[k2[good]]]
    return np.union1d(push, cand)

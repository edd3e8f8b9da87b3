"""The extent a default view frames: the model's main body, not its outliers.

A scan with a few far clumps (poste_france.xyz: 1.4 % of its points up to
190 units from a 21-unit body) has a bounding box that is mostly empty; a
view framing that box shows the scan as specks.  :func:`framing_extent`
finds the main body instead:

1. a robust centre, the per-axis median of (a subsample of) the points;
2. a shell around it, ``FRAMING_BODY_SHELL`` x the ``FRAMING_BODY_QUANTILE``
   quantile of the points' distances to the centre (on a clean model every
   point is inside it: the farthest lies within 1.3 x that quantile on the
   bundled and shared models);
3. the bounding box of all the points inside the shell.

It is used only when it is much smaller than the full box (its diagonal
under ``FRAMING_OUTLIER_RATIO`` of the full one) and leaves out few points
(at most ``FRAMING_OUTLIER_MAX_FRACTION``); otherwise the full box is framed
exactly as before.  One function for the editor's first view and Home,
``splatedit render``'s default camera and the demo; levels of detail,
culling and clip planes keep the true bounds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splatedit.model.cloud import column_bounds
from splatedit.tolerances import (FRAMING_BODY_QUANTILE, FRAMING_BODY_SHELL, FRAMING_OUTLIER_MAX_FRACTION,
                                  FRAMING_OUTLIER_RATIO, FRAMING_SAMPLE_POINTS)

#: points per chunk of the pass over all points (bounded temporaries)
_CHUNK = 1 << 20

#: what the user can do about far points
REMOVE_HINT = "`splatedit convert --remove-outliers`"


@dataclass(frozen=True)
class FramingExtent:
    """The box a default view frames, and the full box.

    Attributes:
        lo, hi: (3,) float64 corners of the framed box (model units): the
            main body's box when :attr:`robust`, else the full box.
        full_lo, full_hi: (3,) float64 corners of the bounding box of all
            the points.
        n_far: points outside the main body's shell (0 when not :attr:`robust`).
        n: number of points.
    """

    lo: np.ndarray
    hi: np.ndarray
    full_lo: np.ndarray
    full_hi: np.ndarray
    n_far: int
    n: int

    @property
    def robust(self) -> bool:
        """True when the main body, not the full box, is framed."""
        return self.n_far > 0

    @property
    def center(self) -> np.ndarray:
        """(3,) float64 centre of the framed box."""
        return (self.lo + self.hi) / 2

    @property
    def radius(self) -> float:
        """Half the framed box's diagonal (model units)."""
        return float(np.linalg.norm(self.hi - self.lo)) / 2

    @property
    def full_radius(self) -> float:
        """Half the full box's diagonal (model units)."""
        return float(np.linalg.norm(self.full_hi - self.full_lo)) / 2

    def note(self) -> str | None:
        """One line for the user when far points are left out of the view, else None."""
        if not self.robust:
            return None
        return (f"{self.n_far:,} point{'s' if self.n_far != 1 else ''} far outside the main body "
                f"(outliers?): {REMOVE_HINT}")


def _full(lo, hi, n) -> FramingExtent:
    return FramingExtent(lo, hi, lo, hi, 0, n)


def _subsample(points: np.ndarray, m: int, seed: int) -> np.ndarray:
    n = len(points)
    if n <= m:
        return points
    idx = np.random.default_rng(seed).choice(n, size=m, replace=False)
    return points[np.sort(idx)]


def framing_extent(points: np.ndarray, *, sample: int = FRAMING_SAMPLE_POINTS, seed: int = 0) -> FramingExtent:
    """The box a default view of ``points`` frames (see the module docstring).

    Args:
        points: (n, 3) float64 positions (model units), n >= 1.
        sample: the centre and the shell come from at most this many points
            (a seeded random subsample: the same points give the same box);
            the box and the count of far points are exact.
    """
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    full_lo, full_hi = column_bounds(pts)
    sub = _subsample(pts, sample, seed)
    centre = np.median(sub, axis=0)
    dist = np.sqrt(np.einsum("ij,ij->i", sub - centre, sub - centre))
    shell = FRAMING_BODY_SHELL * float(np.quantile(dist, FRAMING_BODY_QUANTILE))
    # every point inside the shell (its box's farthest corner is): nothing to leave out
    corner = np.maximum(np.abs(full_hi - centre), np.abs(full_lo - centre))
    if not shell > 0 or float(np.linalg.norm(corner)) <= shell:
        return _full(full_lo, full_hi, n)
    shell2 = shell * shell
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    inside = 0
    m = min(n, _CHUNK)
    diff, dist2 = np.empty((m, 3)), np.empty(m)     # reused: no allocation per chunk
    for a in range(0, n, _CHUNK):
        blk = pts[a:a + _CHUNK]
        d, d2 = diff[:len(blk)], dist2[:len(blk)]
        np.subtract(blk, centre, out=d)
        np.einsum("ij,ij->i", d, d, out=d2)
        keep = d2 <= shell2
        inside += int(np.count_nonzero(keep))
        for j in range(3):          # masked reductions: no copy of the kept rows
            lo[j] = min(lo[j], np.min(blk[:, j], where=keep, initial=np.inf))
            hi[j] = max(hi[j], np.max(blk[:, j], where=keep, initial=-np.inf))
    n_far = n - inside
    full_diag = float(np.linalg.norm(full_hi - full_lo))
    if (inside == 0 or n_far > FRAMING_OUTLIER_MAX_FRACTION * n
            or not np.linalg.norm(hi - lo) < FRAMING_OUTLIER_RATIO * full_diag):
        return _full(full_lo, full_hi, n)
    return FramingExtent(lo, hi, full_lo, full_hi, n_far, n)

"""Screen-space selection brush on a pick map.

A *pick map* is an ``(h, w)`` int array with the index of the front-most splat
per pixel (-1 = background), as the renderer's pick pass returns it.  The
brush is a circle of ``radius`` pixels; a stroke paints every splat whose
pick-map pixels fall inside the circle, so only visible splats are selected.

Splats smaller than a pixel can be missing from the pick map although they
are visible; with projected centres and depths (:class:`BrushPicker` given
``centers_px``/``depths``/``radii``) a splat whose centre falls in the circle
is also painted when it is not behind the splat the pick map shows at that
pixel (depth test against the front surface with a tolerance: the editor
uses the larger of two splat radii and a few pixel footprints, so dense
models give solid, hole-free selections of the visible surface).

The selection itself (support + handles and their paint rules) is
:class:`splatedit.select.selection.Selection`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np



def disc_offsets(radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Integer pixel offsets (dy, dx) within ``radius`` of a pixel centre."""
    r = max(float(radius), 0.5)
    ri = int(math.ceil(r))
    dy, dx = np.mgrid[-ri:ri + 1, -ri:ri + 1]
    keep = dx * dx + dy * dy <= r * r
    return dy[keep], dx[keep]


def indices_in_circle(pick: np.ndarray, cx: float, cy: float, radius: float) -> np.ndarray:
    """Sorted unique splat indices (>= 0) of the pick-map pixels whose centres
    lie within ``radius`` pixels of (cx, cy)."""
    h, w = pick.shape
    r = max(float(radius), 0.5)
    x0, x1 = max(int(math.floor(cx - r)), 0), min(int(math.ceil(cx + r)) + 1, w)
    y0, y1 = max(int(math.floor(cy - r)), 0), min(int(math.ceil(cy + r)) + 1, h)
    if x0 >= x1 or y0 >= y1:
        return np.zeros(0, np.int64)
    ys, xs = np.mgrid[y0:y1, x0:x1]
    inside = (xs + 0.5 - cx) ** 2 + (ys + 0.5 - cy) ** 2 <= r * r
    vals = pick[y0:y1, x0:x1][inside]
    return np.unique(vals[vals >= 0]).astype(np.int64)


def stroke_points(x0: float, y0: float, x1: float, y1: float, radius: float) -> list[tuple[float, float]]:
    """Dab positions from (x0, y0) (exclusive) to (x1, y1) (inclusive) spaced
    at most half a radius apart, so a fast drag leaves no gaps."""
    d = math.hypot(x1 - x0, y1 - y0)
    step = max(radius * 0.5, 1.0)
    n = max(1, int(math.ceil(d / step)))
    return [(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n) for k in range(1, n + 1)]


@dataclass
class BrushPicker:
    """A pick map plus (optionally) projected splat centres for sub-pixel splats.

    Args:
        pick: (h, w) int, splat index per pixel, -1 = background.
        centers_px: (n, 2) float pixel coordinates of the splat centres, or None.
        depths: (n,) camera-space depths (positive in front), or None.
        tol: (n,) depth tolerances (model units): a splat whose centre falls on
            a pixel is visible when it is at most this far behind the front
            surface there; or None.
        pick_depth: (h, w) depth of the front surface per pixel (NaN for the
            background), or None to use the depth of the pixel's front splat.
    """
    pick: np.ndarray
    centers_px: np.ndarray | None = None
    depths: np.ndarray | None = None
    tol: np.ndarray | None = None
    pick_depth: np.ndarray | None = None

    def __post_init__(self):
        self.pick = np.asarray(self.pick)
        self._order = None
        self._all = None          # every projected centre by pixel: (indices, keys, row stride), see covered
        if self.centers_px is not None:
            h, w = self.pick.shape
            px = self.centers_px
            with np.errstate(invalid="ignore"):
                ok = (np.isfinite(px).all(1) & (px[:, 0] >= 0) & (px[:, 0] < w) & (px[:, 1] >= 0)
                      & (px[:, 1] < h) & (self.depths > 0))
            idx = np.flatnonzero(ok)
            ix = px[idx, 0].astype(np.int64)
            iy = px[idx, 1].astype(np.int64)
            front = self.pick[iy, ix]
            has = front >= 0
            if self.pick_depth is not None:
                fd = self.pick_depth[iy, ix]
                has &= np.isfinite(fd)
            else:
                fd = self.depths[np.where(has, front, 0)]
            tol = self.tol[idx] if self.tol is not None else 0.0
            with np.errstate(invalid="ignore"):
                vis = (front == idx) | (has & (self.depths[idx] <= fd + tol))
            idx = idx[vis]
            # bucket visible centres by row for fast circle queries
            rows = px[idx, 1].astype(np.int64)
            order = np.argsort(rows, kind="stable")
            self._vis_idx = idx[order]
            self._vis_rows = rows[order]
            self._order = True

    @property
    def shape(self) -> tuple[int, int]:
        return self.pick.shape

    def visible_centres(self) -> np.ndarray:
        """Indices (int64) of the splats whose projected centre is visible
        (on a pixel, at most ``tol`` behind the front surface there); empty
        without projected centres."""
        return self._vis_idx if self._order is not None else np.zeros(0, np.int64)

    def query(self, cx: float, cy: float, radius: float) -> np.ndarray:
        """Sorted unique indices of the visible splats under the brush circle."""
        out = indices_in_circle(self.pick, cx, cy, radius)
        if self._order is None:
            return out
        r = max(float(radius), 0.5)
        lo = np.searchsorted(self._vis_rows, int(math.floor(cy - r)), "left")
        hi = np.searchsorted(self._vis_rows, int(math.floor(cy + r)), "right")
        cand = self._vis_idx[lo:hi]
        if len(cand):
            p = self.centers_px[cand]
            near = (p[:, 0] - cx) ** 2 + (p[:, 1] - cy) ** 2 <= r * r
            if near.any():
                out = np.union1d(out, cand[near])
        return out


    def covered(self, cx: float, cy: float, radius: float) -> np.ndarray:
        """Sorted unique indices of every splat in front of the camera whose
        centre projects into the brush circle, hidden or not (the dab's 3D
        reach: its circle extruded along the view through the model), plus
        :meth:`query`'s.  Without projected centres: :meth:`query`'s."""
        out = self.query(cx, cy, radius)
        if self.centers_px is None or self.depths is None:
            return out
        if self._all is None:     # every projected centre sorted by pixel (row, column), once per view
            h, w = self.pick.shape
            px = self.centers_px
            with np.errstate(invalid="ignore"):
                ok = np.isfinite(px).all(1) & (self.depths > 0) & (px[:, 0] > -1) & (px[:, 0] < w + 1) \
                    & (px[:, 1] > -1) & (px[:, 1] < h + 1)
            idx = np.flatnonzero(ok)
            key = (np.floor(px[idx, 1]).astype(np.int64) + 1) * (w + 3) + np.floor(px[idx, 0]).astype(np.int64) + 1
            order = np.argsort(key, kind="stable")
            self._all = (idx[order], key[order], w + 3)
        idx, key, stride = self._all
        r = max(float(radius), 0.5)
        rows = np.arange(int(math.floor(cy - r)), int(math.floor(cy + r)) + 1) + 1
        x0, x1 = int(math.floor(cx - r)) + 1, int(math.floor(cx + r)) + 1
        x0, x1 = max(x0, 0), min(x1, stride - 1)
        if x0 > x1 or not len(rows):
            return out
        lo = np.searchsorted(key, rows * stride + x0, "left")
        hi = np.searchsorted(key, rows * stride + x1, "right")
        counts = hi - lo
        if counts.sum() == 0:
            return out
        starts = np.repeat(lo - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
        cand = idx[starts + np.arange(counts.sum())]
        p = self.centers_px[cand]
        near = (p[:, 0] - cx) ** 2 + (p[:, 1] - cy) ** 2 <= r * r
        return np.union1d(out, cand[near])


def picker_for_view(pick: np.ndarray, front_depth: np.ndarray | None, camera, positions: np.ndarray,
                    radii: np.ndarray, tol_px: float = 6.0) -> BrushPicker:
    """The editor's picker for one view: the renderer's pick map and front
    depth plus every splat centre projected with ``camera`` (an
    :class:`~splatedit.app.view.camera_control.OrbitCamera`); a centre counts as
    visible when it lies at most ``max(2 radii, tol_px pixel footprints)``
    behind the front surface."""
    h, w = pick.shape
    px, depth = camera.project(positions, w, h)
    footprint = np.abs(depth) * (camera.world_per_pixel(1.0, h) * tol_px)
    tol = np.maximum(2.0 * np.asarray(radii), footprint)
    return BrushPicker(pick, px, depth, tol, front_depth)


class ViewPicking:
    """The pick map of the editor's current view (an owned part of the
    :class:`~splatedit.app.editor.Editor`, ``editor.picking``): which splat
    is visible at each pixel, as a :class:`BrushPicker`, rebuilt when the
    view or the drawn document changes (taken from the frame scheduler when
    it drew it in chunks after the view's refinement, else picked now).
    Used by the brush, the region tools, clicks on a handle or the support
    and the zoom to the cursor."""

    def __init__(self, ed):
        self._ed = ed
        self._picker: BrushPicker | None = None
        self._key = None

    def key(self) -> tuple:
        """What the pick map depends on: camera, size, the cloud's and the
        basis' revisions, the displacement drawn."""
        from splatedit.app.document import revision
        ed = self._ed
        s = ed.session
        w, h = ed.size
        dc = ed.viewport.dc
        return (ed.cam.state(), w, h, revision.of(s.cloud), revision.of(s.basis),
                None if dc is None or not dc.any() else dc.tobytes())

    def invalidate(self) -> None:
        """Forget the pick map (the drawn cloud was replaced)."""
        self._picker = None

    def current(self) -> bool:
        """The pick map of this view is at hand (no pick needed to use it)."""
        return self._picker is not None and self._key == self.key()

    def get(self) -> BrushPicker:
        """The :class:`BrushPicker` of this view (picked when stale)."""
        from splatedit.tolerances import EDITOR_PICK_TOL_PX
        ed = self._ed
        s = ed.session
        w, h = ed.size
        key = self.key()
        if self._picker is None or self._key != key:
            ready = ed.frames.take_pick(key)     # drawn in chunks after the view's refinement
            idx, front = ready if ready is not None else ed.viewport.pick(ed.cam, w, h)
            self._picker = picker_for_view(idx, front, ed.cam, s.cloud.positions, s.cloud.radii, EDITOR_PICK_TOL_PX)
            self._key = key
        return self._picker

    def splat_under(self, x: float, y: float) -> int:
        """The index of the splat visible at pixel (x, y), or -1."""
        p = self.get().pick
        ix, iy = int(x), int(y)
        if 0 <= iy < p.shape[0] and 0 <= ix < p.shape[1]:
            return int(p[iy, ix])
        return -1

    def displaced(self) -> bool:
        """The view draws a displacement (a move in progress or pending)."""
        dc = self._ed.viewport.dc
        return dc is not None and bool(dc.any())

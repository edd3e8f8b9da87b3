"""The editor's selection tools: the 3D brush, grow / shrink / select
connected / invert, and the closure of the selection after each change.

*3D brush* (the default): the front surface point under the cursor (the
renderer's pick map and front depth) and the brush's on-screen radius
converted at that depth (:meth:`OrbitCamera.world_per_pixel`) define a
sphere; every splat whose centre lies inside it is painted, front and back,
so one stroke along a thin part (an ear, an arm) selects its whole
thickness.  The *visible-only* brush (:class:`~splatedit.app.tools.pick_brush.
BrushPicker`) paints only what the pick map shows.

The tools work on the splats' neighbour graph
(:class:`~splatedit.select.graph.NeighbourGraph`, its cKDTree also answers
the brush's ball queries); it is built once per base cloud, in a background
job for big clouds.  After every stroke and tool the selection is *closed*
(:func:`~splatedit.select.closure.close_selection`: holes of the support
filled, splats enclosed by a handle added to it) so that no unselected splat
stays fixed inside or next to the moving region; what closure added is
highlighted for a moment.  Closure keeps to what the strokes covered and
never gives back an erased splat: the selection remembers both per stroke
(:class:`~splatedit.select.selection.Selection`'s reach and erased marks).

Pure functions here take masks and return masks; :class:`SelectionTools`
holds the editor-side state (brush mode, graph cache, highlight).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from splatedit.app.document import revision
from splatedit.select.selection import SUPPORT, Selection
from splatedit.tolerances import EDITOR_CLOSURE_HIGHLIGHT_S, EDITOR_GRAPH_SYNC_MAX_SPLATS

#: brush modes: the 3D sphere brush (default) and the visible-only brush
BRUSH_3D, BRUSH_VISIBLE = "3d", "visible"
#: the graph job's progress bar label, and the bar's span for each stage of
#: NeighbourGraph.build and the search trees after it (fractions of the job,
#: from a 1M-splat build: k-NN over the tiles 2.1 s, local scales 0.3 s,
#: edges with CSR 0.8 s, global k-d tree 0.9 s, coarse tree + axis orders 0.2 s)
GRAPH_JOB_STAGE = "neighbour graph (3D brush)"
GRAPH_PROGRESS_SPAN = {"finding neighbours": (0.0, 0.49), "neighbour graph: local scales": (0.49, 0.56),
                       "neighbour graph: edges": (0.56, 0.75), "search trees": (0.75, 1.0)}
#: colour of the splats closure added (a brief highlight)
CLOSURE_RGB = (255, 200, 0)


# ------------------------------------------------------------------ sphere
@dataclass(frozen=True)
class BrushSphere:
    """One dab of the 3D brush.

    Attributes:
        center: (3,) float64 world point (model units).
        radius: sphere radius (model units).
        seed: index of the splat under (or nearest to) the cursor.
        depth: camera depth of the surface point (model units).
    """
    center: np.ndarray
    radius: float
    seed: int
    depth: float


def surface_under(pick: np.ndarray, pick_depth: np.ndarray | None, depths: np.ndarray | None,
                  x: float, y: float, radius_px: float) -> tuple[int, float] | None:
    """``(splat index, camera depth)`` of the front surface under pixel
    (x, y), or where the cursor is over the background, of the nearest
    foreground pixel within ``radius_px`` (so a dab across a silhouette still
    paints); None when the brush circle covers only background.

    Args:
        pick: (h, w) int splat index per pixel, -1 background.
        pick_depth: (h, w) front depth per pixel (NaN background), or None.
        depths: (n,) camera depths of the splat centres (used without
            ``pick_depth`` or where it is not finite), or None.
    """
    h, w = pick.shape
    r = max(float(radius_px), 0.5)
    x0, x1 = max(int(math.floor(x - r)), 0), min(int(math.ceil(x + r)) + 1, w)
    y0, y1 = max(int(math.floor(y - r)), 0), min(int(math.ceil(y + r)) + 1, h)
    if x0 >= x1 or y0 >= y1:
        return None
    ys, xs = np.mgrid[y0:y1, x0:x1]
    d2 = (xs + 0.5 - x) ** 2 + (ys + 0.5 - y) ** 2
    ok = (pick[y0:y1, x0:x1] >= 0) & (d2 <= r * r)
    if not ok.any():
        return None
    k = int(np.argmin(np.where(ok, d2, np.inf)))
    iy, ix = y0 + k // (x1 - x0), x0 + k % (x1 - x0)
    seed = int(pick[iy, ix])
    depth = float(pick_depth[iy, ix]) if pick_depth is not None else math.nan
    if not (math.isfinite(depth) and depth > 0) and depths is not None:
        depth = float(depths[seed])
    if not (math.isfinite(depth) and depth > 0):
        return None
    return seed, depth


def brush_sphere(picker, camera, positions: np.ndarray, x: float, y: float, radius_px: float,
                 size: tuple[int, int], displaced: bool = False) -> BrushSphere | None:
    """The 3D brush's sphere for a dab at pixel (x, y).

    The centre is the point at the front surface's depth on the cursor's ray,
    the radius ``radius_px`` pixels at that depth.
    With ``displaced`` (a pending, uncommitted move draws the splats away from
    ``positions`` (n, 3)) the centre is the undeformed position of the splat
    under the cursor instead: the sphere is matched against undeformed
    positions.
    """
    w, h = size
    hit = surface_under(picker.pick, picker.pick_depth, picker.depths, x, y, radius_px)
    if hit is None:
        return None
    seed, depth = hit
    wpp = camera.world_per_pixel(depth, h)
    radius = float(radius_px) * wpp
    if displaced:
        centre = np.asarray(positions[seed], float)
    else:
        centre = camera.point_at_depth(x, y, w, h, depth)
    return BrushSphere(centre, float(radius), seed, depth)


def splats_in_sphere(tree, sphere: BrushSphere) -> np.ndarray:
    """Sorted indices (int64) of the splats whose centres lie in ``sphere``;
    ``tree`` is a cKDTree of the positions."""
    idx = tree.query_ball_point(sphere.center, sphere.radius)
    return np.sort(np.asarray(idx, np.int64))


# ------------------------------------------------------------------ masks
def target_mask(sel: Selection, target: str) -> np.ndarray:
    """The support or the active handle's mask (not a copy)."""
    return sel.support if target == SUPPORT else sel.handle


def grown(sel: Selection, graph, target: str, rings: int = 1) -> np.ndarray:
    """The target's mask (support or active handle) grown by ``rings`` rings
    of the neighour graph; a handle grows only into the support splats of no
    other handle."""
    if target == SUPPORT:
        return graph.grow(sel.support, rings)
    return graph.grow(sel.handle, rings, within=sel.support & ~sel.others())


def shrunk(sel: Selection, graph, target: str, rings: int = 1) -> np.ndarray:
    """The target's mask shrunk by ``rings`` rings (its boundary removed)."""
    return graph.shrink(target_mask(sel, target), rings)


def connected_region(graph, seed: int, reach: np.ndarray | None = None) -> np.ndarray:
    """(n,) bool: the splats connected to ``seed`` over the neighbour graph
    through splats of ``reach`` ((n,) bool, e.g. the brush sphere; None: the
    whole connected component)."""
    return graph.connected(np.array([int(seed)]), reach)


def inverted(sel: Selection, target: str) -> np.ndarray:
    """Support: every splat not in it.  Handle: the support splats not in the
    active handle nor another handle."""
    if target == SUPPORT:
        return ~sel.support
    return sel.support & ~sel.handle & ~sel.others()


def everything(sel: Selection, target: str) -> np.ndarray:
    """Select all: every splat (support), or the support splats of no other
    handle (the active handle)."""
    if target == SUPPORT:
        return np.ones(sel.n, bool)
    return sel.support & ~sel.others()


def set_target(sel: Selection, target: str, mask: np.ndarray) -> bool:
    """Make the target's mask ``mask`` with the brush rules (a handle stays
    inside the support and disjoint from the others; removing support splats
    removes them from every handle).  The tool's result is remembered like a
    stroke's: splats it removed count as erased, those it added as painted.
    Returns True when something changed."""
    old = target_mask(sel, target)
    mask = np.asarray(mask, bool)
    add = np.flatnonzero(mask & ~old)
    rem = np.flatnonzero(old & ~mask)
    changed = sel.paint(rem, target, erase=True)
    changed |= sel.paint(add, target)
    return changed


def apply_closure(sel: Selection, cloud, graph, changed: np.ndarray | None = None,
                  within: Selection | None = None) -> np.ndarray:
    """Close ``sel`` in place (support and every handle, see
    :func:`~splatedit.select.closure.close_selection`; ``changed``: the splats
    painted or erased since the last closure, so only their neighbourhood is
    worked on); returns the (n,) bool mask of the splats closure added to the
    support or a handle.  ``within`` (the selection before an erase stroke):
    the closed support and handles are cut to it, so erasing never makes a
    selection grow.  Closure keeps to the selection's memory (its reach, and
    no erased splat comes back: :meth:`Selection.closure_limits`)."""
    from splatedit.select.closure import close_selection
    if not sel.support.any():
        return np.zeros(sel.n, bool)
    res = close_selection(cloud, sel.support, list(sel.handles), graph=graph, changed=changed,
                          **sel.closure_limits())
    support = np.asarray(res.support, bool)
    handles = [np.asarray(h, bool) for h in res.handles]
    if within is not None:
        support = support & within.support
        handles = [h & within.handles[i] if i < len(within.handles) else h & within.support
                   for i, h in enumerate(handles)]
    before = [sel.support] + list(sel.handles)
    added = np.zeros(sel.n, bool)
    for b, a in zip(before, [support] + handles):
        added |= a & ~b
    sel.support = support.copy()
    taken = np.zeros(sel.n, bool)
    sel.handles = []
    for hm in handles:
        m = hm & support & ~taken
        taken |= m
        sel.handles.append(m)
    if not sel.handles:
        sel.handles.append(np.zeros(sel.n, bool))
    sel.active = min(sel.active, len(sel.handles) - 1)
    return added


def erase_message(before: np.ndarray, after: np.ndarray, what: str) -> str:
    """The status line after an erase stroke of the ``what`` mask (support /
    handle): ``before`` the stroke, ``after`` it and its closure ((n,) bool
    each); "" when the stroke erased nothing.  (Closure never gives erased
    splats back: the selection remembers them.)"""
    gone = int((before & ~after).sum())
    return f"erased {gone:,} splats from the {what}" if gone else ""


# ------------------------------------------------------------------ overlay
def points_patch(px: np.ndarray, size: tuple[int, int], rgb=CLOSURE_RGB, alpha: int = 220, radius: int = 1):
    """An overlay :class:`~splatedit.app.ui.overlay.Patch` with a small square dot
    (side ``2 radius + 1`` pixels) at each pixel position ``px`` (m, 2) inside
    the ``size`` (w, h) window, or None when none is."""
    from splatedit.app.ui.overlay import Patch
    w, h = size
    px = np.asarray(px, float).reshape(-1, 2)
    ok = np.isfinite(px).all(axis=1)
    p = np.floor(px[ok]).astype(np.int64)
    p = p[(p[:, 0] >= 0) & (p[:, 0] < w) & (p[:, 1] >= 0) & (p[:, 1] < h)]
    if not len(p):
        return None
    x0, y0 = p.min(axis=0) - radius
    x1, y1 = p.max(axis=0) + radius + 1
    img = np.zeros((y1 - y0, x1 - x0, 4), np.uint8)
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            img[p[:, 1] - y0 + dy, p[:, 0] - x0 + dx] = (*rgb, alpha)
    return Patch(int(x0), int(y0), img)


# ------------------------------------------------------------------ state
class SelectionTools:
    """Editor-side state of the selection tools: brush mode, the neighbour
    graph of the current base cloud (built in a background :class:`~splatedit.
    app.jobs.Job`, waited for when the cloud is small), the last closure's
    highlight.

    Args:
        start_job: ``start_job(name, fn)`` starts a background job and returns
            it (the editor's job machinery); None builds graphs on the
            calling thread.
    """

    def __init__(self, start_job=None):
        self.mode = BRUSH_3D
        self._start_job = start_job
        self._graphs: dict[int, tuple[object, object]] = {}   # cloud revision -> (cloud, graph)
        self._job = None
        self._job_cloud = None
        self.highlight: np.ndarray | None = None     # (n,) bool: what closure added last
        self.highlight_cloud = None
        self.highlight_until = 0.0
        self.last_added = 0
        self.closure_pending = False                 # a selection changed while no graph was ready
        #: (cloud, support, handles) right after the last closure: the next one
        #: closes only around what changed since (cost follows the stroke)
        self._last_closed = None
        self._failed = None                          # the cloud whose graph failed (not retried)

    # ------------------------------------------------------------ graph
    def toggle_mode(self) -> str:
        self.mode = BRUSH_VISIBLE if self.mode == BRUSH_3D else BRUSH_3D
        return self.mode

    def prepare(self, cloud) -> None:
        """Start building the neighbour graph of ``cloud`` unless it is cached
        or being built."""
        if revision.of(cloud) in self._graphs or self._job_cloud is cloud or self._failed is cloud:
            return
        if self._job is not None:
            self._job.cancel.set()
        positions = cloud.positions

        def work(progress):
            from splatedit.select.graph import NeighbourGraph

            def overall(stage, fraction):        # one bar: the tiles' k-NN, then edges, then the trees
                at = GRAPH_PROGRESS_SPAN.get(stage, (0.0, 1.0))
                progress(GRAPH_JOB_STAGE, at[0] + (at[1] - at[0]) * fraction)

            overall("", 0.0)
            graph = NeighbourGraph.build(positions, progress=overall)
            overall("search trees", 0.0)
            graph.tree
            overall("search trees", 0.8)
            return graph.warm()   # its first closure pays nothing more

        if self._start_job is None:
            self._store(cloud, work(lambda *a: None))
            return
        self._job = self._start_job("neighbour graph", work)
        self._job_cloud = cloud

    def building(self, cloud) -> float | None:
        """The fraction done (0..1) of the background job building ``cloud``'s
        graph, or None when no build for it is running (ready, or not asked)."""
        job = self._job
        if job is None or self._job_cloud is not cloud or job.done:
            return None
        return float(job.fraction)

    def cancel(self) -> None:
        """Abandon a running graph build (quitting): the job stops at its next
        tile or chunk."""
        if self._job is not None:
            self._job.cancel.set()

    def _store(self, cloud, graph) -> None:
        # keep the graphs of the last few base clouds (undo / redo switch between them)
        self._graphs[revision.of(cloud)] = (cloud, graph)
        while len(self._graphs) > 3:
            self._graphs.pop(next(iter(self._graphs)))

    def poll(self) -> bool:
        """Collect a finished graph job; True when a graph became ready."""
        job = self._job
        if job is None or not job.done:
            return False
        cloud = self._job_cloud
        self._job = self._job_cloud = None
        if job.error is None:
            self._store(cloud, job.result)
            return True
        if not job.cancel.is_set():
            self._failed = cloud
        return False

    def graph(self, cloud, wait: bool = True):
        """The neighbour graph of ``cloud``, or None while it is being built
        (``wait``: block for it when the cloud has at most
        EDITOR_GRAPH_SYNC_MAX_SPLATS splats)."""
        got = self._graphs.get(revision.of(cloud))
        if got is not None and got[0] is cloud:
            return got[1]
        self.prepare(cloud)
        got = self._graphs.get(revision.of(cloud))
        if got is not None:
            return got[1]
        if wait and self._job is not None and cloud.n <= EDITOR_GRAPH_SYNC_MAX_SPLATS:
            self._job.wait()
            self.poll()
            got = self._graphs.get(revision.of(cloud))
            return got[1] if got is not None else None
        return None

    # -------------------------------------------------------- closure
    def close(self, session, within: Selection | None = None) -> int | None:
        """Close the session's selection in place (no history entry); returns
        the number of splats closure added, or None when the graph is not
        ready yet (``closure_pending`` is then set).  ``within``: see
        :func:`apply_closure` (an erase stroke's selection before it)."""
        g = self.graph(session.cloud)
        if g is None:
            self.closure_pending = True
            return None
        sel = session.selection
        changed = None
        last = self._last_closed
        if last is not None and last[0] is session.cloud and len(last[2]) == len(sel.handles):
            changed = last[1] ^ sel.support
            for before, now in zip(last[2], sel.handles):
                changed |= before ^ now
        added = apply_closure(sel, session.cloud, g, changed, within)
        self._closed(session, added)
        return self.last_added

    def _closed(self, session, added: np.ndarray) -> None:
        """Bookkeeping after the session's selection was closed (``added``:
        the (n,) bool splats closure added): the next closure's starting
        point, the highlight."""
        sel = session.selection
        self._last_closed = (session.cloud, sel.support.copy(), [h.copy() for h in sel.handles])
        self.closure_pending = False
        self.last_added = int(added.sum())
        if self.last_added:
            self.highlight = added
            self.highlight_cloud = session.cloud
            self.highlight_until = time.perf_counter() + EDITOR_CLOSURE_HIGHLIGHT_S
            session.version += 1

    def highlighted(self, cloud) -> np.ndarray | None:
        """(n,) bool of the splats to highlight now, or None."""
        if (self.highlight is None or self.highlight_cloud is not cloud
                or time.perf_counter() > self.highlight_until):
            return None
        return self.highlight

    # ---------------------------------------------------------- tools
    def background_apply(self, session) -> "BackgroundApply | None":
        """A :class:`BackgroundApply` of the session's brush target (the
        selection copied now), or None while the neighbour graph is built."""
        g = self.graph(session.cloud)
        if g is None:
            return None
        last = self._last_closed
        if last is not None and (last[0] is not session.cloud or len(last[2]) != len(session.selection.handles)):
            last = None
        return BackgroundApply(session, session.brush_target, g, last)

    def install(self, job: "BackgroundApply", label: str) -> bool:
        """Make ``job``'s closed selection the session's (one undo step,
        ``label``); False (nothing changed) when the session, its cloud or
        its selection changed since the job copied it, a move runs, or the
        job changed nothing."""
        s = job.session
        if job.result is None or s.manip is not None or job.key != BackgroundApply.key_of(s):
            return False
        sel, work = s.selection, job.result
        for attr in ("support", "handles", "active", "reach", "erased", "handle_reach", "handle_erased"):
            setattr(sel, attr, getattr(work, attr))
        self._closed(s, job.added)
        s.push(label)
        return True

    def apply(self, session, target: str, mask: np.ndarray, label: str) -> bool:
        """Make the target's mask ``mask`` (see :func:`set_target`), close the
        selection and record both as one undo step; False when nothing changed
        (or a manipulation is running)."""
        if session.manip is not None:
            return False
        if not set_target(session.selection, target, mask):
            return False
        self.close(session)
        session.push(label)
        return True


class BackgroundApply:
    """A selection tool's change made off the main thread (a long one: the
    mirror of half a 1M-splat model): the session's selection is copied
    when it starts (:meth:`SelectionTools.background_apply`), the worker
    sets the brush target's mask on the copy with the brush rules and
    closes it (:meth:`compute`), and the editor installs the result when
    the job lands (:meth:`SelectionTools.install`) unless the selection
    changed meanwhile."""

    def __init__(self, session, target: str, graph, last_closed):
        self.session, self.target, self.graph = session, target, graph
        self.cloud = session.cloud
        self.key = self.key_of(session)
        self.sel = session.selection.copy()
        # what the last closure left (copies: the worker compares against it)
        self._last = None if last_closed is None else (last_closed[1].copy(), [h.copy() for h in last_closed[2]])
        #: the closed selection (None: the mask changed nothing) and what closure added
        self.result: Selection | None = None
        self.added: np.ndarray | None = None

    @staticmethod
    def key_of(session) -> tuple:
        """What must not change between the copy and the install."""
        sel = session.selection
        return (id(session.cloud), revision.of(session.cloud), sel.key(), sel.active, len(sel.handles),
                session.history.position, len(session.history))

    def target_mask(self) -> np.ndarray:
        """(n,) bool: the brush target's mask in the copied selection."""
        return target_mask(self.sel, self.target)

    def compute(self, mask: np.ndarray) -> bool:
        """Worker side: make the copy's target ``mask`` and close it; False
        when ``mask`` changes nothing."""
        sel = self.sel
        if not set_target(sel, self.target, mask):
            return False
        changed = None
        if self._last is not None and len(self._last[1]) == len(sel.handles):
            changed = self._last[0] ^ sel.support
            for before, now in zip(self._last[1], sel.handles):
                changed |= before ^ now
        self.added = apply_closure(sel, self.cloud, self.graph, changed)
        self.result = sel
        return True

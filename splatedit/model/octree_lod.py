"""Which octree nodes to show: screen-space refinement under a point budget.

A COPC / Potree-style octree stores every point of a scan exactly once, in
one node; a node at depth ``d`` holds a subsample of its cube with point
spacing about ``spacing / 2**d`` (``spacing``: the root's).  Showing the
union of a *connected top* of the tree (every shown node's parent shown too)
therefore gives a level of detail made of real points of the file, denser
where deeper nodes are added.

:func:`select_nodes` picks that top the way Potree does (Schuetz 2016,
"Potree: Rendering Large Point Clouds in Web Browsers", Sect. 3.2): start at
the root, repeatedly take the candidate node whose point spacing projects
largest on the screen (the nearest, coarsest ones first), keep it while the
total point count stays within ``budget``, and add its children to the
candidates while its spacing still projects above ``min_px`` pixels.  Nodes
outside the view frustum are not refined.  The returned order is the order
to load in: a parent always comes before its children.

Pure numerics (no file access, no GPU): the nodes come as keys
``(depth, x, y, z)`` with bounds and point counts.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from splatedit.tolerances import NODE_NORMAL_NEIGHBOURS, OCTREE_LOD_MIN_PX, SPACING_NEIGHBOUR


@dataclass(frozen=True)
class OctreeView:
    """The camera as node selection needs it.

    Attributes:
        eye: (3,) float64 camera position (the octree's units and frame).
        view_projection: (4, 4) float64 world -> clip matrix (Vulkan depth
            0..1), used for the frustum test; None: no frustum test.
        fov_y: vertical field of view (radians).
        height_px: viewport height (pixels).
    """
    eye: np.ndarray
    view_projection: np.ndarray | None
    fov_y: float
    height_px: int

    def pixels_per_unit(self, distance: float) -> float:
        """Pixels one model unit covers at camera distance ``distance`` (> 0)."""
        return self.height_px / (2.0 * math.tan(self.fov_y / 2.0) * distance)


def frustum_planes(view_projection: np.ndarray) -> np.ndarray:
    """(6, 4) inward planes ``(a, b, c, d)``, ``a x + b y + c z + d >= 0``
    inside, of a Vulkan-style clip matrix (x, y in -w..w, depth 0..w)
    (Gribb & Hartmann's row combinations)."""
    m = np.asarray(view_projection, dtype=np.float64)
    r0, r1, r2, r3 = m
    return np.stack([r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2])


def box_outside(planes: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    """True when the box ``lo..hi`` lies entirely outside one of ``planes``
    (conservative: a box reported inside may still miss the frustum)."""
    far = np.where(planes[:, :3] >= 0.0, hi, lo)         # the box corner farthest inside each plane
    return bool((np.einsum("ij,ij->i", planes[:, :3], far) + planes[:, 3] < 0.0).any())


def box_distance(point: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """Euclidean distance from ``point`` to the box ``lo..hi`` (0 inside)."""
    return float(np.linalg.norm(np.maximum(np.maximum(lo - point, point - hi), 0.0)))


def node_spacing(root_spacing: float, depth: int) -> float:
    """Point spacing of the nodes at ``depth`` (model units)."""
    return root_spacing / float(2 ** depth)


def projected_spacing(view: OctreeView, root_spacing: float, depth: int,
                      lo: np.ndarray, hi: np.ndarray) -> float:
    """Pixels the point spacing of a node at ``depth`` with bounds ``lo..hi``
    covers where the node is nearest to the eye (the eye inside: the spacing
    itself as distance, so the value stays finite)."""
    s = node_spacing(root_spacing, depth)
    return s * view.pixels_per_unit(max(box_distance(view.eye, lo, hi), s))


def children_of(key: tuple) -> list[tuple]:
    """The 8 possible child keys of ``(depth, x, y, z)``."""
    d, x, y, z = (int(k) for k in key)
    return [(d + 1, 2 * x + i, 2 * y + j, 2 * z + k) for i in (0, 1) for j in (0, 1) for k in (0, 1)]


@dataclass(frozen=True)
class NodeChoice:
    """The outcome of :func:`select_nodes`.

    Attributes:
        keys: the chosen node keys in load order (parents before children,
            the largest projected spacing first).
        points: their total point count.
        complete: True when no visible node still projects above ``min_px``
            and was left out for the budget (the view is fully refined).
    """
    keys: tuple
    points: int
    complete: bool


def select_nodes(nodes: dict, root_spacing: float, view: OctreeView, *, budget: int,
                 min_px: float = OCTREE_LOD_MIN_PX, always=()) -> NodeChoice:
    """Choose the nodes to show from ``view`` within ``budget`` points.

    Args:
        nodes: key ``(depth, x, y, z)`` (any 4-sequence, e.g. a NamedTuple)
            -> an object with ``point_count`` and ``bounds`` ((2, 3) float64
            min / max corner); the root is the key of depth 0.
        root_spacing: the root's point spacing (model units, > 0).
        view: the camera (:class:`OctreeView`).
        budget: most points to choose (the root is chosen even above it).
        min_px: a node is refined (its children become candidates) while its
            spacing projects above this many pixels.
        always: keys counted first and always kept (e.g. an edit region loaded
            at full resolution); their points count towards the budget.
    Returns:
        :class:`NodeChoice`; ``keys`` holds the keys as given in ``nodes``.
    """
    if root_spacing <= 0 or not math.isfinite(root_spacing):
        raise ValueError(f"root spacing must be positive, got {root_spacing}")
    by_tuple = {tuple(int(v) for v in k): k for k in nodes}
    planes = frustum_planes(view.view_projection) if view.view_projection is not None else None
    chosen: list = []
    seen: set = set()
    total = 0
    for k in always:
        t = tuple(int(v) for v in k)
        if t in by_tuple and t not in seen:
            seen.add(t)
            chosen.append(by_tuple[t])
            total += int(nodes[by_tuple[t]].point_count)
    roots = [t for t in by_tuple if t[0] == 0]
    heap: list = []
    tie = 0

    def push(t: tuple) -> None:
        nonlocal tie
        b = np.asarray(nodes[by_tuple[t]].bounds, dtype=np.float64)
        px = projected_spacing(view, root_spacing, t[0], b[0], b[1])
        visible = planes is None or not box_outside(planes, b[0], b[1])
        # visible nodes first, then by projected spacing (largest first), then coarse first
        heapq.heappush(heap, (0 if visible else 1, -px, t[0], tie, t, visible, px))
        tie += 1

    for t in roots:
        push(t)
    complete = True
    while heap:
        _, _, _, _, t, visible, px = heapq.heappop(heap)
        count = int(nodes[by_tuple[t]].point_count)
        if t not in seen:
            if total + count > budget and t[0] > 0:
                if visible and px > min_px:
                    complete = False
                continue            # too big for what is left: smaller nodes may still fit
            seen.add(t)
            chosen.append(by_tuple[t])
            total += count
        if visible and px > min_px:
            for c in children_of(t):
                if c in by_tuple and c not in seen:
                    push(c)
    return NodeChoice(tuple(chosen), total, complete)


# ----------------------------------------------------------------- splats of shown nodes
def node_frames(points: np.ndarray, k: int = NODE_NORMAL_NEIGHBOURS,
                spacing_k: int = SPACING_NEIGHBOUR) -> tuple[np.ndarray, np.ndarray]:
    """Normals and spacings of one node's points, from the node alone.

    A node holds a subsample of its cube at about its depth's spacing, so its
    own k nearest neighbours give a PCA normal (Hoppe et al. 1992) and the
    distance to the ``spacing_k``-th neighbour (the splat size rule of
    :func:`splatedit.model.estimate.splat_radii`) without the rest of the
    scan: each node is estimated once, when it is loaded.  Normals are oriented
    with a non-negative z (scans of the ground are Z-up).  The sign of a
    near-vertical normal (a wall) is arbitrary here, and the splat renderer
    culls splats facing away unless two-sided drawing is on (the editor's T),
    so such a wall can be hidden from one side.

    Args:
        points: (n, 3) float64 positions (model units).
    Returns:
        normals (n, 3) float32 unit, spacing (n,) float32 model units (> 0;
        1.0 for a single point).
    """
    from scipy.spatial import cKDTree

    from splatedit.model.estimate import estimate_normals
    pts = np.ascontiguousarray(points, dtype=np.float64)
    n = len(pts)
    if n < 3:
        nrm = np.zeros((n, 3), np.float32)
        nrm[:, 2] = 1.0
        sp = np.full(n, float(np.ptp(pts, axis=0).max()) if n == 2 else 1.0, np.float32)
        return nrm, np.maximum(sp, 1e-9).astype(np.float32)
    kk = int(min(max(k, spacing_k + 1), n))
    dist, nb = cKDTree(pts).query(pts, kk, workers=-1)
    nrm = estimate_normals(pts, min(k, n), neighbours=nb)
    nrm[nrm[:, 2] < 0] *= -1.0
    sp = dist[:, min(spacing_k, kk - 1)]
    good = sp[np.isfinite(sp) & (sp > 0)]
    med = float(np.median(good)) if len(good) else 1.0
    sp = np.where(np.isfinite(sp) & (sp > 0.05 * med), sp, med)
    return nrm.astype(np.float32), sp.astype(np.float32)


def key_codes(keys) -> np.ndarray:
    """(m,) int64 codes of ``(depth, x, y, z)`` keys (depth < 8, coordinates
    < 2**20): equal keys, equal codes."""
    a = np.asarray([tuple(int(v) for v in k) for k in keys], dtype=np.int64).reshape(-1, 4)
    return (a[:, 0] << 60) | (a[:, 1] << 40) | (a[:, 2] << 20) | a[:, 3]


def finest_shown(points: np.ndarray, key: tuple, shown_codes: np.ndarray, cube_lo: np.ndarray,
                 cube_size: float, max_depth: int) -> tuple[np.ndarray, np.ndarray]:
    """For the points of node ``key``: the code and depth of the deepest shown
    node whose cube holds each point (the node itself at least).

    Args:
        points: (n, 3) float64 positions in the octree's frame.
        key: the points' node ``(depth, x, y, z)``.
        shown_codes: sorted int64 :func:`key_codes` of the shown nodes.
        cube_lo: (3,) the root cube's lower corner; ``cube_size`` its edge.
        max_depth: the octree's deepest level.
    Returns:
        codes (n,) int64, depths (n,) int64.
    """
    d0 = int(key[0])
    n = len(points)
    ijk = np.tile(np.asarray(key[1:], dtype=np.int64), (n, 1))
    code = np.full(n, key_codes([key])[0], dtype=np.int64)
    depth = np.full(n, d0, dtype=np.int64)
    alive = np.ones(n, bool)
    rel = (np.asarray(points, dtype=np.float64) - cube_lo) / cube_size      # 0..1 in the root cube
    for d in range(d0 + 1, max_depth + 1):
        if not alive.any():
            break
        cells = np.clip(np.floor(rel * (1 << d)).astype(np.int64), ijk * 2, ijk * 2 + 1)
        c = (np.int64(d) << 60) | (cells[:, 0] << 40) | (cells[:, 1] << 20) | cells[:, 2]
        pos = np.searchsorted(shown_codes, c)
        hit = alive & (pos < len(shown_codes)) & (shown_codes[np.minimum(pos, len(shown_codes) - 1)] == c)
        code[hit], depth[hit] = c[hit], d
        ijk = np.where(hit[:, None], cells, ijk)
        alive = hit
    return code, depth

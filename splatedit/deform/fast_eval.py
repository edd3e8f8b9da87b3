"""Fast evaluation of a fitted triharmonic RBF and its gradient at many points.

The deformation basis needs ``f(x) = sum_j w_j ||x - c_j||^3 + p(x)`` and its
gradient at every free support splat: N points times n centres, about 3.5-4.5
ns per (point, centre) pair of one core here in float64.  The RBF centres lie
on the constraint bands only; away from them f is smooth (triharmonic), which
the hierarchical far-field evaluation of Carr et al. 2001 (SIGGRAPH,
"Reconstruction and representation of 3D objects with radial basis
functions") exploits.  Here in its simplest, target-side form with tensor
Chebyshev interpolation of the smooth part (as in Fong & Darve 2009, J.
Comput. Phys., "The black-box fast multipole method"):

* the query points are split into boxes (k-d: the middle of the longest
  side; the points are permuted so that a box is a range of rows);
* a box's *near* sources are the centres within ``(1 + separation)`` half
  diagonals of its centre, the rest its *far* sources;
* the far sources' field and gradient are interpolated from their exact
  float64 values at the box's p^3 Chebyshev nodes (p = FAST_EVAL_NODES), the
  near sources' are evaluated directly in float64; a box with near sources
  and more than FAST_EVAL_LEAF points is split first;
* error control per box: the interpolant is compared with the exact far
  field at FAST_EVAL_CHECK_POINTS of the box's own points; a box whose error
  exceeds ``tol * value_scale`` is split, or evaluated directly when small.

Direct evaluation (near sources, small boxes, nodes) is BLAS-3: squared
distances from one GEMM ``[x, 1, |x|^2] @ [-2 c^T; |c|^2; 1]``, then ``r^3``
and the gradient sums ``sum_j w_j r_ij (1, c_j)`` as two more GEMMs, in
cache-sized row chunks.  float32 there was measured 9e-3 off (relative to
the largest value, 400k-splat support): the weights are large and cancel, so
only the interpolation (weights and values of order 1) runs in float32.
Box tasks run on EVAL_THREADS threads with BLAS held to one thread.

Everything works in normalised coordinates; the caller applies the chain rule
for the gradient (``d/dx = (1 / scale) d/dxn``).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from splatedit.blas import single_blas_thread
from splatedit.deform.kernels import poly_gradient_coefficients, poly_matrix
from splatedit.tolerances import (
    EVAL_THREADS,
    FAST_EVAL_CHECK_POINTS,
    FAST_EVAL_CHUNK_ROWS,
    FAST_EVAL_LEAF,
    FAST_EVAL_NODES,
    FAST_EVAL_SEPARATION as SEPARATION,
)


#: rows of a box interpolated at once (bounds the (rows, p^2 + p * 4k) float32
#: temporaries to about 1 MB per thread)
_BOX_BLOCK = 2048


@dataclass
class FastEvalStats:
    """What :func:`evaluate` did.

    Attributes:
        n_points: query points.
        n_centers: RBF centres.
        n_direct: points evaluated directly against every centre.
        n_interpolated: points whose far field was interpolated from box nodes.
        n_boxes: interpolated boxes; ``n_nodes`` their Chebyshev nodes (all
            evaluated exactly in float64, as are the ``n_checks`` check points).
        n_rejected: boxes whose interpolant failed the check (then split).
        max_check_error: largest error at the check points of accepted boxes,
            relative to the scale the tolerance is measured in.
        pairs: (point, centre) pairs evaluated in all (direct + nodes + checks).
    """

    n_points: int = 0
    n_centers: int = 0
    n_direct: int = 0
    n_interpolated: int = 0
    n_boxes: int = 0
    n_nodes: int = 0
    n_checks: int = 0
    n_rejected: int = 0
    max_check_error: float = 0.0
    pairs: int = 0


class RBFField:
    """The RBF part ``sum_j w_j ||x - c_j||^3`` of a fitted field and its
    gradient, in normalised coordinates, with the polynomial ``p`` added.

    Args:
        centers: (n, 3) float64 normalised centres.
        weights: (n, k) float64 weights.
        poly_coeffs: (10, k) monomial coefficients or None.
    """

    def __init__(self, centers: np.ndarray, weights: np.ndarray, poly_coeffs):
        self.centers = np.ascontiguousarray(centers, dtype=np.float64)
        self.weights = np.ascontiguousarray(weights, dtype=np.float64)
        self.k = self.weights.shape[1]
        c = self.centers
        n = len(c)
        self.n = n
        self.poly = None if poly_coeffs is None else np.asarray(poly_coeffs, dtype=np.float64)
        self._pgrad = None if self.poly is None else poly_gradient_coefficients(self.poly)
        # [-2 c^T; |c|^2; 1] for the GEMM form of the squared distances and
        # [W, c_x W, c_y W, c_z W] for the gradient sums (see rbf_at)
        self._aug = np.ascontiguousarray(
            np.vstack([-2.0 * c.T, (c * c).sum(axis=1), np.ones(n)]) if n else np.zeros((5, 0)))
        self._gw = np.ascontiguousarray(
            np.concatenate([self.weights] + [c[:, d:d + 1] * self.weights for d in range(3)], axis=1)
            if n else np.zeros((0, 4 * self.k)))

    # ------------------------------------------------------------ direct
    def rbf_at(self, x: np.ndarray, sources: np.ndarray | None = None) -> np.ndarray:
        """(rows, 4k) float64 ``[f, df/dx, df/dy, df/dz]`` of the RBF part
        (no polynomial) at normalised ``x`` (rows, 3), summed over the centres
        ``sources`` (indices; all when None), directly in float64 and in row
        chunks of FAST_EVAL_CHUNK_ROWS (the (rows, n) work matrices stay in
        cache).  Squared distances come from one GEMM (BLAS-3); in
        normalised coordinates its cancellation error is about 1e-16 in r^2.
        (float32 here was measured 9e-3 off relative to the largest value on a
        400k-splat support: the weights are large and cancel.)"""
        k, rows = self.k, len(x)
        out = np.zeros((rows, 4 * k))
        if sources is None:
            aug, w, gw = self._aug, self.weights, self._gw
        else:
            if len(sources) == 0:
                return out
            aug, w, gw = self._aug[:, sources], self.weights[sources], self._gw[sources]
        if aug.shape[1] == 0:
            return out
        step = FAST_EVAL_CHUNK_ROWS
        xa = np.empty((min(step, rows), 5))
        for s in range(0, rows, step):
            xc = x[s:s + step]
            xs = xa[:len(xc)]
            xs[:, :3] = xc
            xs[:, 3] = 1.0
            xs[:, 4] = (xc * xc).sum(axis=1)
            d2 = xs @ aug
            np.maximum(d2, 0.0, out=d2)
            r = np.sqrt(d2)
            d2 *= r
            o = out[s:s + step]
            np.matmul(d2, w, out=o[:, :k])
            sums = r @ gw
            for d in range(3):
                o[:, (d + 1) * k:(d + 2) * k] = 3.0 * (xc[:, d:d + 1] * sums[:, :k]
                                                       - sums[:, (d + 1) * k:(d + 2) * k])
        return out

    def add_polynomial(self, x: np.ndarray, out: np.ndarray) -> None:
        """Add the polynomial's values and gradient to ``out`` (rows, 4k)."""
        if self.poly is None or len(x) == 0:
            return
        k = self.k
        out[:, :k] += poly_matrix(x) @ self.poly
        x1 = np.empty((len(x), 4))
        x1[:, 0] = 1.0
        x1[:, 1:] = x
        for d in range(3):
            out[:, (d + 1) * k:(d + 2) * k] += x1 @ self._pgrad[d]


# ------------------------------------------------------------------ boxes
def _cheb_nodes(p: int) -> tuple[np.ndarray, np.ndarray]:
    """Chebyshev points of the first kind on [-1, 1] and their barycentric weights."""
    i = np.arange(p)
    theta = (2 * i + 1) * np.pi / (2 * p)
    return np.cos(theta), (-1.0) ** i * np.sin(theta)


def _lagrange(t: np.ndarray, nodes: np.ndarray, bw: np.ndarray) -> np.ndarray:
    """(len(t), p) Lagrange basis values at ``t`` (barycentric formula)."""
    diff = t[:, None] - nodes[None, :]
    exact = diff == 0.0
    diff[exact] = 1.0
    q = bw[None, :] / diff
    q /= q.sum(axis=1, keepdims=True)
    hit = exact.any(axis=1)
    if hit.any():
        q[hit] = exact[hit].astype(np.float64)
    return q


class _Box:
    """Rows ``a:b`` of the permuted points and their bounding box."""

    __slots__ = ("a", "b", "lo", "hi")

    def __init__(self, a, b, lo, hi):
        self.a, self.b, self.lo, self.hi = a, b, lo, hi

    def __len__(self) -> int:
        return self.b - self.a

    @property
    def half_diag(self) -> float:
        return 0.5 * float(np.linalg.norm(self.hi - self.lo))

    @property
    def centre(self) -> np.ndarray:
        return 0.5 * (self.lo + self.hi)


def _split(xt, perm, box):
    """Two boxes: ``box`` cut at the middle of its longest side (None when its
    points coincide); its columns of the (3, N) coordinates ``xt`` and its
    entries of ``perm`` are reordered in place (left part first).  (Coordinates by rows: the bounding
    boxes are contiguous reductions, 30x faster than over (n, 3) columns.)"""
    ax = int(np.argmax(box.hi - box.lo))
    mid = 0.5 * (box.lo[ax] + box.hi[ax])
    seg = xt[:, box.a:box.b]
    left = seg[ax] <= mid
    order = np.concatenate([np.flatnonzero(left), np.flatnonzero(~left)])
    xt[:, box.a:box.b] = seg[:, order]
    perm[box.a:box.b] = perm[box.a:box.b][order]
    cut = box.a + int(left.sum())
    if cut in (box.a, box.b):
        return None  # all points coincide: nothing to split
    out = []
    for a, b in ((box.a, cut), (cut, box.b)):
        if b > a:
            part = xt[:, a:b]
            out.append(_Box(a, b, part.min(axis=1), part.max(axis=1)))
    return out


def _box_nodes(box, nodes1d):
    """(p^3, 3) tensor Chebyshev nodes of ``box`` and the per-axis maps."""
    c, h = box.centre, 0.5 * (box.hi - box.lo)
    h = np.where(h > 0, h, 1.0)
    ax = [c[d] + h[d] * nodes1d for d in range(3)]
    g = np.stack(np.meshgrid(*ax, indexing="ij"), axis=-1).reshape(-1, 3)
    return g, c, h


def _interpolate(xb, c, h, nodes1d, bw, fv32):
    """Tensor Chebyshev interpolant at ``xb`` (rows, 3) of the node values
    ``fv32`` (p, p, p * cols) float32, as (rows, cols) float64: one GEMM over
    the (x, y) node pairs, then the z sum (weights and values are O(1), so
    float32 adds about 1e-7 relative)."""
    p = len(nodes1d)
    lx, ly, lz = (_lagrange((xb[:, d] - c[d]) / h[d], nodes1d, bw).astype(np.float32)
                  for d in range(3))
    lxy = (lx[:, :, None] * ly[:, None, :]).reshape(len(xb), p * p)
    g = (lxy @ fv32.reshape(p * p, -1)).reshape(len(xb), p, -1)
    return np.einsum("rlc,rl->rc", g, lz, dtype=np.float64)


def evaluate(field_: RBFField, x: np.ndarray, *, tol: float, value_scale: float,
             nodes: int = FAST_EVAL_NODES, separation: float = SEPARATION,
             leaf: int = FAST_EVAL_LEAF, checks: int = FAST_EVAL_CHECK_POINTS,
             threads: int = EVAL_THREADS, far_field: bool = True):
    """Values and gradients ``[f, df/dx, df/dy, df/dz]`` (N, 4k) float64 at
    normalised points ``x`` (N, 3).

    Boxes of points (a k-d split at the middle of the longest side) are
    classified against the RBF centres: the centres within ``(1 +
    separation)`` half diagonals of a box's centre are its *near* sources, the
    rest its *far* sources.  A box with at least ``2 p^3 + checks`` points whose
    near sources are none, or which is at most ``leaf`` points, gets the far
    sources' field and gradient by tensor Chebyshev interpolation from their
    exact float64 values at its p^3 nodes, and the near sources' directly
    (float64); larger boxes with near sources are split.  The interpolant is
    checked at ``checks`` of the box's points against the exact far field; a
    box whose error exceeds ``tol * value_scale`` (values, and gradients per
    normalised unit) is split, or evaluated directly when it is small.
    Boxes too small to interpolate are evaluated directly.

    Args:
        field_: the :class:`RBFField`.
        x: (N, 3) normalised query points.
        tol: relative error allowed at the check points.
        value_scale: what ``tol`` is relative to (the largest constraint value).
        nodes: Chebyshev nodes per axis (p).
        separation, leaf, checks: see above.
        threads: worker threads (BLAS on one thread meanwhile).
        far_field: False evaluates every point directly (the exact reference).
    Returns:
        ``(out, stats)``: (N, 4k) float64 and a :class:`FastEvalStats`.
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    n_pts, k, n_src = len(x), field_.k, field_.n
    stats = FastEvalStats(n_points=n_pts, n_centers=n_src)
    out = np.empty((n_pts, 4 * k))
    if n_pts == 0:
        return out, stats
    nodes1d, bw = _cheb_nodes(nodes)
    n_nodes = nodes ** 3
    min_interp = 2 * n_nodes + checks  # interpolation must beat direct evaluation
    limit = tol * value_scale
    workers = max(1, int(threads))
    pool = ThreadPoolExecutor(max_workers=workers) if workers > 1 else None
    rng = np.random.default_rng(0)
    all_src = np.arange(n_src)
    xt = np.ascontiguousarray(x.T)  # (3, N) points, permuted so that every box is a range
    xp = xt.T                      # (N, 3) view of them; xp = x[perm]
    perm = np.arange(n_pts)
    outp = np.empty((n_pts, 4 * k))
    direct = []                    # boxes evaluated directly

    def run(fn, items):
        return list(map(fn, items)) if pool is None else list(pool.map(fn, items))

    def box_task(item):
        """Interpolate the far field of one box and add its near field;
        returns (ok, error at the checks, pairs evaluated)."""
        b, near, chk = item
        far = all_src if near is None else np.setdiff1d(all_src, near, assume_unique=True)
        g, c, h = _box_nodes(b, nodes1d)
        xc = xp[chk]
        fv = field_.rbf_at(np.concatenate([g, xc]), far)
        fv32 = fv[:n_nodes].reshape(nodes, nodes, -1).astype(np.float32)
        err = float(np.max(np.abs(_interpolate(xc, c, h, nodes1d, bw, fv32) - fv[n_nodes:])))
        pairs = (n_nodes + len(chk)) * len(far)
        if err > limit:
            return False, err, pairs
        # in row blocks: the interpolation's temporaries stay a few MB per thread
        for a in range(b.a, b.b, _BOX_BLOCK):
            e = min(a + _BOX_BLOCK, b.b)
            xb = xp[a:e]
            res = outp[a:e]
            res[:] = _interpolate(xb, c, h, nodes1d, bw, fv32)
            if near is not None and len(near):
                res += field_.rbf_at(xb, near)
                pairs += len(xb) * len(near)
        return True, err, pairs

    with single_blas_thread():
        try:
            if far_field and n_src and n_pts >= min_interp:
                from scipy.spatial import cKDTree
                tree = cKDTree(field_.centers)
                todo = [_Box(0, n_pts, xt.min(axis=1), xt.max(axis=1))]
                while todo:
                    cand, nxt = [], []
                    dist = tree.query(np.array([b.centre for b in todo]))[0]
                    for b, d in zip(todo, dist):
                        reach = (1.0 + separation) * b.half_diag
                        if len(b) < min_interp:
                            direct.append(b)
                        elif d >= reach:
                            cand.append((b, None))
                        elif len(b) > leaf:
                            parts = _split(xt, perm, b)
                            (direct.append(b) if parts is None else nxt.extend(parts))
                        else:
                            near = np.sort(np.asarray(tree.query_ball_point(b.centre, reach),
                                                      dtype=np.intp))
                            if len(near) < n_src:
                                cand.append((b, near))
                            else:              # nothing far: direct
                                direct.append(b)
                    items = [(b, near, b.a + rng.choice(len(b), min(checks, len(b)), replace=False))
                             for b, near in cand]
                    for (b, near, _), (ok, err, pairs) in zip(items, run(box_task, items)):
                        stats.pairs += pairs
                        stats.n_checks += checks
                        if ok:
                            stats.n_boxes += 1
                            stats.n_nodes += n_nodes
                            stats.n_interpolated += len(b)
                            stats.max_check_error = max(stats.max_check_error,
                                                        err / max(value_scale, 1e-300))
                        else:
                            stats.n_rejected += 1
                            parts = _split(xt, perm, b) if len(b) >= 2 * min_interp else None
                            (direct.append(b) if parts is None else nxt.extend(parts))
                    todo = nxt
            else:
                direct.append(_Box(0, n_pts, None, None))
            step = FAST_EVAL_CHUNK_ROWS
            parts = [(a, min(a + step, b.b)) for b in direct for a in range(b.a, b.b, step)]
            stats.n_direct = int(sum(len(b) for b in direct))
            stats.pairs += stats.n_direct * n_src

            def direct_rows(ab):
                outp[ab[0]:ab[1]] = field_.rbf_at(xp[ab[0]:ab[1]])

            run(direct_rows, parts)
            # the polynomial, exactly, everywhere
            step = 65536
            run(lambda s: field_.add_polynomial(xp[s:s + step], outp[s:s + step]),
                range(0, n_pts, step))
            out[perm] = outp
        finally:
            if pool is not None:
                pool.shutdown()
    return out, stats

"""CPU hot path of the detail mode (:meth:`DetailBasis.apply_arrays`).

Per frame and support splat the detail mode needs the deformed base point
``b' = b + d(b)`` and the images ``J t1``, ``J t2`` of the base tangent frame
(see :mod:`splatedit.deform.detail`).  With a rotating handle h the base is
deformed rotation-aware (:mod:`splatedit.deform.rotation`): with
``K = [w_h / |w_h|]x`` and the arc coefficients ``a1, a2, b1, b2`` of the
splat's weight ``s_h`` (:func:`~splatedit.deform.rotation.arc_coefficients`)

    b'   = [B | b] [dC; I] + a1 K v + a2 K^2 v,       v   = B_h offsets_h
    J t  = [W | t] [dC; I] + a1 K g + a2 K^2 g + (b1 K v + b2 K^2 v) (grad s_h . t),
                                                      g   = W_h offsets_h

(``W = t_x Bx + t_y By + t_z Bz``, ``W_h`` its columns of handle h).  ``K v``
and ``K^2 v`` are linear in the basis rows, ``B_h (offsets_h K^T)``, so they
come out of the same GEMM as ``b'`` (3 more output columns each per
rotating handle), and ``s_h``, ``grad s_h . t`` do not depend on the frame
(precomputed).  What is left per splat is element-wise: the arc
coefficients (two sines), the products above and the re-attachment.

Layout: like :class:`~splatedit.deform.basis.DeformationBasis` (its run plan
of the support indices, small gaps of fixed splats computed through and
restored bitwise), but transposed: the hot-path arrays are (K + 3, M) with
one splat per column, the GEMM is ``X^T (c', K + 3) @ A (K + 3, c)`` and every
element-wise step works on contiguous (c,) rows of sub-chunks of
``DETAIL_APPLY_CHUNK`` splats (they stay in cache); results are written by
slice for long runs of consecutive indices, by index only for the rest.
"""

from __future__ import annotations

import numpy as np

from splatedit.deform.apply_plan import APPLY_STAGE, fill_small_gaps, run_plan
from splatedit.deform.rotation import arc_coefficients, handle_blocks
from splatedit.deform.rotation_apply import skew
from splatedit.progress import report
from splatedit.tolerances import DETAIL_APPLY_CHUNK


class DetailHotPath:
    """The hot-path arrays of one :class:`~splatedit.deform.detail.DetailBasis`
    (about 24 (K + 3) + 80 + 24 h bytes per support splat, h handles).

    Args:
        basis: the DetailBasis (its base basis rows, layer and axis coordinates).
        n_points: splats of the cloud it applies to.
    """

    def __init__(self, basis, n_points: int):
        bb, lay = basis.base_basis, basis.layer
        idx = basis.indices
        span, member = fill_small_gaps(idx)
        order, self.segments = run_plan(span)
        sel = member[order]                               # plan columns that are support splats
        prow = (np.cumsum(member) - 1)[order][sel]        # their rows in the basis / layer
        m, k = len(order), bb.n_columns
        pk = bb._pack[prow]                               # (N, 4, K)
        t1, t2 = (t[prow] for t in basis._t)
        # filler columns (fixed splats computed through, restored afterwards):
        # zero basis rows and the frame (e_x, e_y), so nothing divides by zero
        self.arrays = []
        for src, fill in ((None, None), (t1, 0), (t2, 1)):
            a = np.zeros((k + 3, m))
            if src is None:
                a[:k, sel] = pk[:, 0, :].T
                a[k:, sel] = lay.base[prow].T
            else:
                a[:k, sel] = np.einsum("nj,njk->kn", src, pk[:, 1:, :])
                a[k:, sel] = src.T
                a[k + fill, ~sel] = 1.0
            self.arrays.append(a)
        self.offset = np.zeros(m)
        self.offset[sel] = lay.offset[prow]
        self.cu = np.zeros((3, m))
        self.cv = np.zeros((3, m))
        self.cu[:, sel] = basis._cu[prow].T
        self.cv[:, sel] = basis._cv[prow].T
        # per handle: the weight s_h and grad s_h . t1, grad s_h . t2 (frame-independent)
        self.blocks = handle_blocks(bb)
        self.weights, self.grads = [], []
        for cols in self.blocks:
            s = np.zeros(m)
            s[sel] = pk[:, 0, cols].sum(axis=1)
            self.weights.append(s)
            self.grads.append(tuple(a[cols].sum(axis=0) for a in self.arrays[1:]))
        self.filler = span[~member]
        self.comp_segments = None
        if 2 * len(span) > n_points:      # the support is most of the cloud: copy only the rest
            comp = np.setdiff1d(np.arange(n_points), span, assume_unique=True)
            self.comp_segments = [d for _, _, d in run_plan(comp, chunk=1 << 30)[1]]
        self.n_columns = k

    # ------------------------------------------------------------ per frame
    def _frame_matrix(self, d: np.ndarray, rot):
        """``X^T`` (3 + 6 r, K + 3) of the frame and the rotating handles
        ``[(h, angle), ...]`` (r of them)."""
        k = self.n_columns
        turning = [] if rot is None else rot.rotating
        x = np.zeros((k + 3, 3 + 6 * len(turning)))
        x[:k, :3] = d
        x[k:, :3] = np.eye(3)
        for i, h in enumerate(turning):
            r = rot.rotations[h]
            km = skew(r.w / r.angle)
            cols = self.blocks[h]
            x[cols, 3 + 6 * i:6 + 6 * i] = r.offsets @ km.T
            x[cols, 6 + 6 * i:9 + 6 * i] = r.offsets @ (km @ km).T
        return np.ascontiguousarray(x.T), [(h, rot.rotations[h].angle) for h in turning]

    def apply(self, srcs, d: np.ndarray, rot, rigid: bool, progress=None):
        """Deformed ``(positions, u, v)`` (n, 3) float64 from the cloud's
        ``srcs`` = (positions, u, v), the residual dC ``d`` (K, 3) and the
        RotationDisplacement ``rot`` (or None); ``rigid``: FrameMode.RIGID.
        ``progress``: optional ``progress(APPLY_STAGE, fraction of rows done)``
        after each chunk."""
        if self.comp_segments is None:
            outs = tuple(s.copy() for s in srcs)
        else:
            outs = tuple(np.empty_like(s) for s in srcs)
            for dest in self.comp_segments:
                for s, o in zip(srcs, outs):
                    o[dest] = s[dest]
        xt, turning = self._frame_matrix(d, rot)
        a0, a1, a2 = self.arrays
        step = DETAIL_APPLY_CHUNK
        total = max(1, a0.shape[1])
        for lo, hi, dest in self.segments:
            for cs in range(lo, hi, step):
                ce = min(hi, cs + step)
                o0, o1, o2 = xt @ a0[:, cs:ce], xt @ a1[:, cs:ce], xt @ a2[:, cs:ce]
                mb, j1, j2 = o0[:3], o1[:3], o2[:3]
                for i, (h, theta) in enumerate(turning):
                    c1, c2, e1, e2 = arc_coefficients(theta, self.weights[h][cs:ce])
                    q = slice(3 + 6 * i, 6 + 6 * i)
                    q2 = slice(6 + 6 * i, 9 + 6 * i)
                    fv = e1 * o0[q]
                    fv += e2 * o0[q2]
                    mb += c1 * o0[q]
                    mb += c2 * o0[q2]
                    g1, g2 = self.grads[h]
                    for j, oj, g in ((j1, o1, g1), (j2, o2, g2)):
                        j += c1 * oj[q]
                        j += c2 * oj[q2]
                        j += fv * g[cs:ce]
                p, u, v = _attach_rows(mb, j1, j2, self.offset[cs:ce], self.cu[:, cs:ce],
                                       self.cv[:, cs:ce], rigid)
                if isinstance(dest, slice):
                    rows = slice(dest.start + cs - lo, dest.start + ce - lo)
                else:
                    rows = dest[cs - lo:ce - lo]
                for o, r in zip(outs, (p, u, v)):
                    o[rows] = r.T
                report(progress, APPLY_STAGE, ce / total)
        if len(self.filler):            # fixed splats computed through: restore them bitwise
            for s, o in zip(srcs, outs):
                o[self.filler] = s[self.filler]
        return outs


def _attach_rows(mb, j1, j2, offset, cu, cv, rigid: bool):
    """Re-attached (p', u', v') (3, c) each from the rows (3, c) of the
    deformed base ``mb`` (modified in place), ``j1`` = J t1 and ``j2`` = J t2,
    the offsets (c,) and the axis coordinates ``cu``, ``cv`` (3, c) in the
    base frame (t1, t2, n_b); see :func:`splatedit.deform.detail._attach`."""
    n = np.empty_like(mb)
    np.multiply(j1[1], j2[2], out=n[0])
    n[0] -= j1[2] * j2[1]
    np.multiply(j1[2], j2[0], out=n[1])
    n[1] -= j1[0] * j2[2]
    np.multiply(j1[0], j2[1], out=n[2])
    n[2] -= j1[1] * j2[0]
    inv = np.einsum("ij,ij->j", n, n)
    np.sqrt(inv, out=inv)
    np.divide(1.0, inv, out=inv)
    n *= inv
    mb += offset * n
    if rigid:   # orthonormalise [J t1, J t2]: (A^T A)^-1/2 by the 2x2 formula
        e = np.einsum("ij,ij->j", j1, j1)
        f = np.einsum("ij,ij->j", j1, j2)
        g = np.einsum("ij,ij->j", j2, j2)
        sd = np.sqrt(e * g - f * f)
        t = np.sqrt(e + g + 2 * sd)
        s00, s01, s11 = (e + sd) / t, f / t, (g + sd) / t
        det = s00 * s11 - s01 * s01
        i00, i01, i11 = s11 / det, -s01 / det, s00 / det
        j1, j2 = j1 * i00 + j2 * i01, j1 * i01 + j2 * i11
    u = j1 * cu[0]
    u += j2 * cu[1]
    u += n * cu[2]
    v = j1 * cv[0]
    v += j2 * cv[1]
    v += n * cv[2]
    return mb, u, v

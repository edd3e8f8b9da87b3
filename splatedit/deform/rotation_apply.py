"""CPU hot path of the rotation-aware mode (:meth:`DeformationBasis.apply_arrays`
of a :class:`~splatedit.deform.rotation.RotationDisplacement`).

Per frame and support splat the mode needs (:mod:`splatedit.deform.rotation`)

    p' = [B | p] [dC; I] + sum_h a1 K v + a2 K^2 v,              v = B_h offsets_h
    u' = [Wu | u] [dC; I] + sum_h a1 K g + a2 K^2 g + (b1 K v + b2 K^2 v) (grad s_h . u)

with ``K = [w_h / |w_h|]x``, ``g = Wu_h offsets_h`` (``Wu = u_x Bx + u_y By +
u_z Bz``, the tangent-axis rows of the linear mode's hot path, ``Wu_h`` its
columns of handle h), the arc coefficients ``a1, a2, b1, b2`` of the weight
``s_h`` (:func:`~splatedit.deform.rotation.arc_coefficients`, here from one
tangent: :func:`arc_coefficients_tan`) and likewise
for ``v'``.  Everything but the arc coefficients is linear in the rows of the
linear mode's three hot-path arrays ``[B | p]``, ``[Wu | u]``, ``[Wv | v]``:
``K v = B_h (offsets_h K^T)``, ``s_h = B_h 1`` and ``grad s_h . u = Wu_h 1``.
So one frame matrix ``X`` (K + 3, 3 + 7 r) for r rotating handles (the
linear ``[dC; I]``, then per handle ``offsets K^T``, ``offsets K^2T`` and
the handle's column sum) gives every term from the same three GEMMs, over the
same cached arrays and run plan as the linear mode (no per-splat memory is
added; ``DeformationBasis.release_cpu_cache`` frees them all).

The products are taken transposed, ``X^T (3 + 7 r, K + 3) @ A^T (K + 3, c)``
(BLAS reads the row-major chunk of A as its transpose, no copy), so every
element-wise step runs on contiguous (c,) rows, in sub-chunks of at most
:data:`~splatedit.tolerances.ROTATION_APPLY_CHUNK` splats that stay in
cache and small enough that OpenBLAS runs each product on one thread
(:func:`chunk_rows`; its threads only contend on a loaded machine).  For
long runs of consecutive splat indices the last sums write straight into
the output slices (viewed transposed), the rest is written by index.  The
results equal the unfused :func:`~splatedit.deform.rotation.apply_rotation`
up to the order of floating-point sums (within 1e-14 relative measured;
``tests/deform/test_rotation.py``).
"""

from __future__ import annotations

import numpy as np

from splatedit.deform.rotation import series_fill
from splatedit.tolerances import BLAS_SINGLE_THREAD_MNK, ROTATION_APPLY_CHUNK, ROTATION_APPLY_MIN_CHUNK


def skew(k: np.ndarray) -> np.ndarray:
    """(3, 3) matrix of ``k x``."""
    return np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])


def frame_matrix(d: np.ndarray, rot, blocks) -> tuple[np.ndarray, list[float]]:
    """``X^T`` (3 + 7 r, K + 3) float64 of one frame and the angles (radians)
    of its r rotating handles.

    Args:
        d: (K, 3) float64 residual control-frame displacements.
        rot: the frame's RotationDisplacement.
        blocks: per handle the slice of its 4 basis columns.
    Rows of the result: 0-2 the linear ``[dC; I]``; then per rotating handle
    i, from ``3 + 7 i``: ``offsets K^T`` (3 rows), ``offsets K^2T`` (3 rows) and
    the handle's column sum (1 row: ``s_h`` from ``[B | p]``, ``grad s_h . u``
    from ``[Wu | u]``).
    """
    k = d.shape[0]
    turning = rot.rotating
    x = np.zeros((k + 3, 3 + 7 * len(turning)))
    x[:k, :3] = d
    x[k:, :3] = np.eye(3)
    angles = []
    for i, h in enumerate(turning):
        r = rot.rotations[h]
        km = skew(r.w / r.angle)
        cols, c0 = blocks[h], 3 + 7 * i
        x[cols, c0:c0 + 3] = r.offsets @ km.T
        x[cols, c0 + 3:c0 + 6] = r.offsets @ (km @ km).T
        x[cols, c0 + 6] = 1.0
        angles.append(r.angle)
    return np.ascontiguousarray(x.T), angles


def arc_coefficients_tan(theta: float, s: np.ndarray):
    """:func:`~splatedit.deform.rotation.arc_coefficients` from one tangent:
    ``sin x = 2 t / (1 + t^2)`` and ``1 - cos x = 2 t^2 / (1 + t^2)`` with
    ``t = tan(x / 2)`` (exact identities for every x; numpy's float64 tan is
    vectorised and about 5x faster than its sin here: 12 against 62 us per
    7,500 values), the rest as there (same closed forms, same series below
    ``|x| = 1e-3``).  Agrees with it within 1e-12 of theta (a1, a2) and
    theta^2 (b1, b2) (both lose digits to the same cancellation in b1 near the
    series switch; ``tests/deform/test_rotation.py``).

    Args:
        theta: the angle (radians, > 0).
        s: (N,) float64 weights.
    Returns:
        (a1, a2, b1, b2), each (N,) float64.
    """
    x = np.multiply(s, theta)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):   # x = 0: replaced below
        t = np.multiply(x, 0.5)
        np.tan(t, out=t)
        d = np.multiply(t, t)
        omc = d.copy()
        d += 1.0
        np.divide(2.0, d, out=d)                    # 2 / (1 + t^2)
        omc *= d                                    # 1 - cos x
        sn = t
        sn *= d                                     # sin x
        inv = np.divide(1.0, x)
        f1 = sn * inv                               # sin x / x
        f2 = omc * inv                              # (1 - cos x) / x
        g1 = np.subtract(1.0, omc)
        g1 -= f1
        g1 *= inv                                   # (x cos x - sin x) / x^2
        g2 = np.subtract(sn, f2)
        g2 *= inv                                   # (x sin x - 1 + cos x) / x^2
    series_fill(x, f1, f2, g1, g2)
    f1 *= theta
    f2 *= theta
    g1 *= theta * theta
    g2 *= theta * theta
    return f1, f2, g1, g2


def add_rotation(o0: np.ndarray, o1: np.ndarray, o2: np.ndarray, angles, dests=None) -> None:
    """Add the blended rotations to the linear rows of one sub-chunk.

    Args:
        o0, o1, o2: (3 + 7 r, c) float64 ``X^T A^T`` of the position and the
            two axis arrays; rows 0-2 (the linear p', u', v') are updated in
            place.
        angles: the r (>= 1) rotating handles' angles (radians), in the order
            of :func:`frame_matrix`.
        dests: None, or three (3, c) views (transposed slices of the output
            arrays) that receive the final p', u', v' instead of rows 0-2
            (the last sum writes them: no separate transposing copy).
    """
    rows = [o0[:3], o1[:3], o2[:3]]
    last = len(angles) - 1
    t, fv = np.empty_like(rows[0]), np.empty_like(rows[0])
    for i, theta in enumerate(angles):
        q = slice(3 + 7 * i, 6 + 7 * i)             # K v, K g
        q2 = slice(6 + 7 * i, 9 + 7 * i)            # K^2 v, K^2 g
        si = 9 + 7 * i                              # s_h, grad s_h . u, grad s_h . v
        a1, a2, b1, b2 = arc_coefficients_tan(theta, o0[si])
        kv, k2v = o0[q], o0[q2]
        np.multiply(b1, kv, out=fv)
        np.multiply(b2, k2v, out=t)
        fv += t                                     # F'(s) v
        np.multiply(a1, kv, out=t)
        rows[0] += t
        np.multiply(a2, k2v, out=t)                 # F(s) v = a1 K v + a2 K^2 v
        out = (dests[0] if dests is not None and i == last else rows[0])
        np.add(rows[0], t, out=out)
        for j, oj in ((1, o1), (2, o2)):
            np.multiply(a1, oj[q], out=t)
            rows[j] += t
            np.multiply(a2, oj[q2], out=t)
            rows[j] += t
            np.multiply(fv, oj[si], out=t)
            out = (dests[j] if dests is not None and i == last else rows[j])
            np.add(rows[j], t, out=out)


def chunk_rows(n_out: int, n_in: int) -> int:
    """Splats per sub-chunk for ``(n_out, n_in) @ (n_in, c)`` products: at most
    ROTATION_APPLY_CHUNK (cache), and m n k below BLAS_SINGLE_THREAD_MNK so
    that OpenBLAS keeps each product on one thread (not below
    ROTATION_APPLY_MIN_CHUNK: the per-call overhead)."""
    fit = (BLAS_SINGLE_THREAD_MNK - 1) // (n_out * n_in)
    return int(max(ROTATION_APPLY_MIN_CHUNK, min(ROTATION_APPLY_CHUNK, fit)))


def apply_segments(arrays, segments, outs, d: np.ndarray, rot, blocks, progress=None) -> None:
    """Write the deformed support splats of a rotating frame into ``outs``.

    Args:
        arrays: the linear mode's hot-path arrays ``[B|p], [Wu|u], [Wv|v]``,
            each (M, K + 3) float64 in run-plan order.
        segments: the run plan ``(lo, hi, dest)``: rows ``lo:hi`` of the arrays
            go to splat rows ``dest`` (a slice or an index array).
        outs: (positions, u, v) (n, 3) float64 output arrays.
        d: (K, 3) float64 residual dC; rot: the RotationDisplacement;
        blocks: per handle the slice of its 4 columns.
        progress: optional ``progress(rows done)`` after each chunk.
    """
    xt, angles = frame_matrix(d, rot, blocks)
    step = chunk_rows(*xt.shape)
    bufs = [np.empty(xt.shape[0] * step) for _ in arrays]    # the GEMM outputs, reused
    for lo, hi, dest in segments:
        for cs in range(lo, hi, step):
            ce = min(hi, cs + step)
            o0, o1, o2 = (np.matmul(xt, a[cs:ce].T, out=b[:xt.shape[0] * (ce - cs)].reshape(-1, ce - cs))
                          for a, b in zip(arrays, bufs))
            if isinstance(dest, slice):            # the last sums write the outputs
                rows = slice(dest.start + cs - lo, dest.start + ce - lo)
                add_rotation(o0, o1, o2, angles, [o[rows].T for o in outs])
            else:
                add_rotation(o0, o1, o2, angles)
                rows = dest[cs - lo:ce - lo]
                for o, r in zip(outs, (o0, o1, o2)):
                    o[rows] = r[:3].T
            if progress is not None:
                progress(ce)

"""CPU hot path of the linear deformation basis (:meth:`DeformationBasis.apply_arrays
<splatedit.deform.basis.DeformationBasis.apply_arrays>`).

Per frame a support splat needs only linear combinations of ``dC``:
``p' = [B | p] @ [dC; I]``, ``u' = [Wu | u] @ [dC; I]`` with
``Wu = u_x Bx + u_y By + u_z Bz`` (the tangent-axis basis) and likewise for
``v``.  :func:`build_hot_path` builds these three (N, K + 3) float64 arrays
once per base cloud, stored in the order of a run plan of the support indices
(:func:`run_plan`: long runs of consecutive splat indices are written with a
slice, the rest gathered into chunks and scattered; :func:`fill_small_gaps`
computes through short gaps of fixed splats so that many short runs become a
few long GEMMs); :func:`apply_hot_path` then runs three chunked GEMMs per
frame straight into the output arrays and copies the splats outside the
support bitwise (one plain copy of the cloud, or only the complement's runs
when the support is most of the cloud).  float64 is kept: float32 would lose
positional accuracy (p is part of the GEMM) and showed no reliable gain in
measurements here (the product is memory- and call-bound).  A rotating frame
(:class:`~splatedit.deform.rotation.RotationDisplacement`) uses the same
arrays and run plan with extra output columns
(:mod:`splatedit.deform.rotation_apply`); the detail mode reuses the run plan
(:mod:`splatedit.deform.detail_apply`).
"""

from __future__ import annotations

import numpy as np

from splatedit.deform.rotation_apply import apply_segments
from splatedit.tolerances import BLAS_SINGLE_THREAD_MNK, LINEAR_APPLY_CHUNK, ROTATION_APPLY_MIN_CHUNK

#: progress stages of a commit (:meth:`DeformationBasis.commit
#: <splatedit.deform.basis.DeformationBasis.commit>`): the support's chunks
#: deformed, then the deformed cloud checked
APPLY_STAGE = "applying the edit"
CHECK_STAGE = "checking the deformed splats"
#: most plan rows per run-plan segment (the linear apply works through a
#: segment in sub-chunks of :func:`apply_chunk_rows`; the detail mode in its own)
_APPLY_CHUNK = 65536
#: plan rows per block while building the hot-path arrays (bounds the
#: gathered copies of basis rows and cloud arrays to a few MB)
_BUILD_BLOCK = 65536
#: a gap of non-support splats between two runs of support splats is computed
#: through (with zero basis rows, then restored bitwise) when it is at most this
#: fraction of the shorter neighbouring run: one long GEMM instead of one call
#: per run (a 1M-splat support made of 1000 grid rows: 35 ms -> see PERFORMANCE.md)
_GAP_FILL_REL = 0.25
#: runs of consecutive splat indices at least this long are written by slice
_RUN_MIN = 512


def fill_small_gaps(index: np.ndarray, rel: float = _GAP_FILL_REL, run_min: int | None = None):
    """Sorted splat indices plus the rows of the small gaps between their runs.

    Returns ``(span, member)``: ``span`` (M,) sorted indices (``index`` and
    the filled gap rows), ``member`` (M,) bool, True where ``span`` is in
    ``index``.  A gap is filled when it is at most ``rel`` times the shorter of
    its two neighbouring runs and both runs have at least ``run_min`` splats,
    so scattered indices (short runs) are left alone.
    """
    index = np.asarray(index)
    run_min = _RUN_MIN if run_min is None else run_min
    n = len(index)
    if n < 2:
        return index, np.ones(n, dtype=bool)
    gaps = np.diff(index) - 1
    breaks = np.flatnonzero(gaps > 0)
    if len(breaks) == 0:
        return index, np.ones(n, dtype=bool)
    starts = np.concatenate([[0], breaks + 1])
    ends = np.concatenate([breaks + 1, [n]])
    run_len = ends - starts
    shorter = np.minimum(run_len[:-1], run_len[1:])
    fill = (gaps[breaks] <= rel * shorter) & (shorter >= run_min)
    if not fill.any():
        return index, np.ones(n, dtype=bool)
    lo = index[breaks[fill]] + 1
    hi = index[breaks[fill] + 1]
    extra = np.concatenate([np.arange(a, b) for a, b in zip(lo, hi)])
    span = np.concatenate([index, extra])
    member = np.concatenate([np.ones(n, dtype=bool), np.zeros(len(extra), dtype=bool)])
    order = np.argsort(span, kind="stable")
    return span[order], member[order]


def run_plan(index: np.ndarray, run_min: int = _RUN_MIN, chunk: int = _APPLY_CHUNK):
    """Split sorted splat indices into segments ``(order_lo, order_hi, dest)``.

    ``order`` (returned) permutes positions of ``index`` so that every segment
    is a contiguous block ``order[order_lo:order_hi]``; ``dest`` is a slice of
    splat rows (long runs of consecutive indices) or an index array (the
    remaining splats, in chunks).
    """
    n = len(index)
    if n == 0:
        return np.zeros(0, np.intp), []
    breaks = np.flatnonzero(np.diff(index) != 1) + 1
    starts = np.concatenate([[0], breaks])
    ends = np.concatenate([breaks, [n]])
    long_mask = (ends - starts) >= run_min
    segments, order_parts, pos = [], [], 0
    for s, e in zip(starts[long_mask], ends[long_mask]):
        for cs in range(s, e, chunk):
            ce = min(e, cs + chunk)
            order_parts.append(np.arange(cs, ce))
            segments.append((pos, pos + ce - cs, slice(int(index[cs]), int(index[cs]) + ce - cs)))
            pos += ce - cs
    short = np.ones(n, dtype=bool)
    for s, e in zip(starts[long_mask], ends[long_mask]):
        short[s:e] = False
    rest = np.flatnonzero(short)
    for cs in range(0, len(rest), chunk):
        part = rest[cs:cs + chunk]
        order_parts.append(part)
        segments.append((pos, pos + len(part), index[part]))
        pos += len(part)
    order = np.concatenate(order_parts) if order_parts else np.zeros(0, np.intp)
    return order, segments


def apply_chunk_rows(n_columns: int) -> int:
    """Splats per GEMM of the linear apply, ``(c, K + 3) @ (K + 3, 3)``: at
    most LINEAR_APPLY_CHUNK, and m n k below BLAS_SINGLE_THREAD_MNK so that
    OpenBLAS keeps every product on one thread (at least
    ROTATION_APPLY_MIN_CHUNK rows, the same per-call overhead)."""
    fit = (BLAS_SINGLE_THREAD_MNK - 1) // (3 * (n_columns + 3))
    return int(max(ROTATION_APPLY_MIN_CHUNK, min(LINEAR_APPLY_CHUNK, fit)))


def build_hot_path(pack: np.ndarray, indices: np.ndarray, cloud) -> dict:
    """Hot-path arrays ``[B|p], [Wu|u], [Wv|v]`` in run-plan order.

    Built in blocks of _BUILD_BLOCK plan rows: besides the arrays it returns
    (3 (K + 3) 8 bytes per plan row) it needs only a few (M,) index arrays
    and one block's gathered rows.

    Args:
        pack: (N, 4, K) float64 basis rows B, Bx, By, Bz of the support splats.
        indices: (N,) sorted cloud indices of the support splats.
        cloud: the base :class:`~splatedit.model.cloud.SplatCloud` (n splats).
    Returns a dict: ``positions``, ``u``, ``v`` (the cloud arrays it was built
    from, for the cache check), ``arrays`` (three (M, K + 3) float64),
    ``segments`` (the run plan), ``comp_segments`` (the complement's runs or
    None) and ``filler`` (the fixed splats computed through).
    """
    # computing through small gaps of fixed splats (restored afterwards) turns
    # many short runs into a few long GEMMs
    span, member = fill_small_gaps(indices)
    order, segments = run_plan(span)
    rank = np.cumsum(member) - 1                      # plan position -> row in pack
    k = pack.shape[2]
    srcs = (cloud.positions, cloud.u, cloud.v)
    arrays = [np.empty((len(order), k + 3)) for _ in srcs]
    for s in range(0, len(order), _BUILD_BLOCK):
        blk = order[s:s + _BUILD_BLOCK]
        rows = span[blk]
        sel = member[blk]                             # block rows that are support splats
        pk = pack[rank[blk[sel]]]                     # (b, 4, K) gathered basis rows
        for j, (src, a) in enumerate(zip(srcs, arrays)):
            ab = a[s:s + len(blk)]
            x = src[rows]
            ab[:, k:] = x
            if j == 0:
                ab[sel, :k] = pk[:, 0, :]
            else:
                ab[sel, :k] = np.einsum("nj,njk->nk", x[sel], pk[:, 1:, :])
            ab[~sel, :k] = 0.0
    filler = span[~member]
    # when the support is most of the cloud, copy only its complement
    # (long runs by slice, the rest by index); otherwise one plain copy
    comp_segments = None
    n_all = len(cloud.positions)
    if 2 * len(span) > n_all:
        comp = np.ones(n_all, dtype=bool)
        comp[span] = False
        comp_segments = [d for _, _, d in run_plan(np.flatnonzero(comp), chunk=1 << 30)[1]]
    return dict(positions=cloud.positions, u=cloud.u, v=cloud.v, arrays=arrays,
                segments=segments, comp_segments=comp_segments, filler=filler)


def apply_hot_path(c: dict, srcs, d: np.ndarray, rot=None, blocks=None, progress=None):
    """Deformed ``(positions, u, v)`` (n, 3) float64 from the hot path ``c``.

    Needs the three outputs and one sub-chunk's products (index-array
    segments) besides them.

    Args:
        c: :func:`build_hot_path` of the base cloud whose arrays are ``srcs``.
        srcs: the base cloud's (positions, u, v), (n, 3) float64 each.
        d: (K, 3) float64 control-point displacements dC.
        rot, blocks: a rotating frame's rotations and handle blocks
            (:mod:`splatedit.deform.rotation_apply`), or None.
        progress: optional ``progress(rows of the hot path done)`` after each chunk.
    """
    # splats outside the support: bitwise copies (never recomputed)
    if c["comp_segments"] is None:
        outs = tuple(s.copy() for s in srcs)
    else:
        outs = tuple(np.empty_like(s) for s in srcs)
        for dest in c["comp_segments"]:
            for s, o in zip(srcs, outs):
                o[dest] = s[dest]
    if rot is not None:   # rotating handles: extra GEMM columns (splatedit.deform.rotation_apply)
        apply_segments(c["arrays"], c["segments"], outs, d, rot, blocks, progress=progress)
    else:
        mx = np.vstack([d, np.eye(3)])
        step = apply_chunk_rows(d.shape[0])
        for lo, hi, dest in c["segments"]:
            for cs in range(lo, hi, step):
                ce = min(hi, cs + step)
                if isinstance(dest, slice):
                    rows = slice(dest.start + cs - lo, dest.start + ce - lo)
                    for a, o in zip(c["arrays"], outs):
                        np.matmul(a[cs:ce], mx, out=o[rows])
                else:
                    rows = dest[cs - lo:ce - lo]
                    for a, o in zip(c["arrays"], outs):
                        o[rows] = a[cs:ce] @ mx
                if progress is not None:
                    progress(ce)
    if len(c["filler"]):  # fixed splats computed through: restore them bitwise
        for s, o in zip(srcs, outs):
            o[c["filler"]] = s[c["filler"]]
    return outs

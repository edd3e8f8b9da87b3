"""The incremental (blocked) Householder QR of Botsch & Kobbelt 2005, Sect. 5.

:class:`IncrementalQR` grows a Householder QR of a tall matrix panel by panel
(left-looking, BLAS-3 panels) and keeps ``Q^T b`` current, so the
least-squares residual of every prefix column count is known as the columns
arrive; the RBF fit (:mod:`splatedit.deform.rbf_fit`) builds its columns
lazily into it.  :func:`blocked_qr` runs it over a prebuilt matrix (tests and
benchmarks).
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from scipy.linalg import lapack

from splatedit.errors import SolverError
from splatedit.tolerances import IQR_PANEL_COLUMNS


class IncrementalQR:
    """Householder QR of a tall matrix grown panel by panel (left-looking).

    Implements Sect. 5 of the paper with BLAS-3 panels instead of single
    columns.  For every new panel of columns:

    1. the reflectors of every previous panel are applied to it, one blocked
       ``dgemqrt`` call per previous panel (compact WY form ``I - V T V^T``
       with the ``T`` stored at factorisation time, so it is never recomputed);
    2. the panel's lower part is factored by ``dgeqrt`` (recursive, BLAS-3);
    3. its reflectors are applied to the right-hand sides, so ``Q^T b`` is
       always current;
    4. the residual of *every* prefix column count inside the panel follows
       for free: ``||b - A[:, :n] x*|| = ||(Q^T b)[n:]||``.  Rows ``n:`` are
       only ever touched by orthogonal reflectors from column ``n`` on, so the
       tail norm is the same whether read right after column ``n`` or later.

    The working panel is kept as a C-ordered (n_rows, w) array: its transpose
    is Fortran-ordered and every row block ``[off:]`` of the panel is a
    Fortran-contiguous column block of the transpose, so step 1 runs
    ``dgemqrt(side="R")`` on the transpose in place, without copies.

    Storage: the reflector blocks ``V_p`` (trapezoidal, the used columns of
    A below the diagonal), their ``T`` factors, and R as per-panel column
    blocks ``R[:j1, j0:j1]``; nothing is allocated for columns never used, so
    memory is O(n_rows * n) for n used columns.
    """

    def __init__(self, n_rows: int, max_cols: int, rhs: np.ndarray):
        if max_cols > n_rows:
            raise ValueError("IncrementalQR needs max_cols <= n_rows")
        self.n_rows = n_rows
        self.max_cols = max_cols
        self.r_blocks = []  # column blocks R[:j1, j0:j1] of the upper triangle
        self.qtb = np.array(rhs, dtype=np.float64, order="F", copy=True)
        if self.qtb.ndim != 2 or self.qtb.shape[0] != n_rows:
            raise ValueError("rhs must have shape (n_rows, k)")
        self.panels = []  # (offset, V (n_rows - offset, w) Fortran, T (w, w))
        self.n_cols = 0
        self._panel = None

    def panel(self, width: int) -> np.ndarray:
        """A writable (n_rows, w) block for the next ``w <= width`` columns."""
        width = min(width, self.max_cols - self.n_cols)
        self._panel = np.empty((self.n_rows, width), dtype=np.float64, order="C")
        return self._panel

    def add_panel(self) -> np.ndarray:
        """Factor the columns written into the last :meth:`panel` block.

        Returns ``tails`` of shape (w + 1, k): ``tails[i] = ||(Q^T b)[j0+i:]||``
        for the prefixes ``n = j0 .. j0 + w`` columns.
        """
        c = self._panel
        if c is None:
            raise ValueError("call panel() first")
        self._panel = None
        j0 = self.n_cols
        width = c.shape[1]
        j1 = j0 + width
        ct = c.T  # Fortran-ordered (w, n_rows) view of the same memory
        # 1. previous reflectors: C[off:] <- Q_p^T C[off:]  <=>  Ct[:, off:] <- Ct[:, off:] Q_p
        for off, v, t in self.panels:
            blk = ct[:, off:]
            out, info = lapack.dgemqrt(v, t, blk, side="R", trans="N", overwrite_c=1)
            if info != 0:  # pragma: no cover - argument error, a bug
                raise SolverError(f"LAPACK dgemqrt failed (info={info})")
            if not np.shares_memory(out, blk):  # pragma: no cover - f2py copied
                blk[...] = out
        # 2. factor the part on and below the diagonal
        v, t, info = lapack.dgeqrt(width, np.asfortranarray(c[j0:]), overwrite_a=1)
        if info != 0:  # pragma: no cover
            raise SolverError(f"LAPACK dgeqrt failed (info={info})")
        self.r_blocks.append(np.vstack([c[:j0], np.triu(v[:width])]))
        self.panels.append((j0, v, t))
        # 3. update Q^T b
        y = np.asfortranarray(self.qtb[j0:])
        y, info = lapack.dgemqrt(v, t, y, side="L", trans="T", overwrite_c=1)
        self.qtb[j0:] = y
        self.n_cols = j1
        # 4. tail norms ||(Q^T b)[n:]|| for n = j0..j1: reverse cumulative sums
        #    (summed from the bottom, so small tails keep their accuracy)
        sq = y * y
        tails_sq = np.zeros((sq.shape[0] + 1, sq.shape[1]))  # last row: empty tail
        tails_sq[:-1] = np.cumsum(sq[::-1], axis=0)[::-1]
        return np.sqrt(tails_sq[: width + 1])

    def r_factor(self, n: Optional[int] = None) -> np.ndarray:
        """The upper-triangular n x n factor R (a new Fortran array)."""
        n = self.n_cols if n is None else n
        if not 0 <= n <= self.n_cols:
            raise ValueError(f"n must be in [0, {self.n_cols}]")
        r = np.zeros((n, n), order="F")
        for (j0, _, _), blk in zip(self.panels, self.r_blocks):
            if j0 >= n:
                break
            w = min(blk.shape[1], n - j0)
            r[: min(blk.shape[0], n), j0:j0 + w] = blk[:n, :w]
        return r

    def r_diagonal(self, n: Optional[int] = None) -> np.ndarray:
        """The first ``n`` diagonal entries of R."""
        n = self.n_cols if n is None else n
        d = [np.diag(blk[j0:]) for (j0, _, _), blk in zip(self.panels, self.r_blocks)]
        return np.concatenate(d)[:n] if d else np.zeros(0)

    def solve(self, n: int) -> np.ndarray:
        """Least-squares solution using the first ``n`` columns: R x = (Q^T b)[:n]."""
        if n == 0:
            return np.zeros((0, self.qtb.shape[1]))
        x, info = lapack.dtrtrs(self.r_factor(n), self.qtb[:n])
        if info > 0:
            raise SolverError(
                f"the least-squares system is singular: R[{info - 1},{info - 1}] = 0 "
                f"(linearly dependent basis functions)")
        if info < 0:  # pragma: no cover
            raise SolverError(f"LAPACK dtrtrs failed (info={info})")
        return x


def blocked_qr(a: np.ndarray, b: np.ndarray, panel: int = IQR_PANEL_COLUMNS):
    """Blocked incremental QR of a prebuilt matrix with all its columns.

    Returns ``(qr, tails)`` where ``qr`` is the :class:`IncrementalQR` state and
    ``tails[n] = ||(Q^T b)[n:]||`` for ``n = 0..ncols``.  Used by tests (oracle:
    ``scipy.linalg.qr``) and the benchmark; the RBF fit builds its columns
    lazily instead.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if b.ndim == 1:
        b = b[:, None]
    qr = IncrementalQR(a.shape[0], a.shape[1], b)
    tails = [None]
    j = 0
    while j < a.shape[1]:
        w = min(panel, a.shape[1] - j)
        qr.panel(w)[...] = a[:, j:j + w]
        t = qr.add_panel()
        if tails[0] is None:
            tails[0] = t[:1]
        tails.append(t[1:])
        j += w
    if tails[0] is None:
        tails[0] = np.sqrt(np.sum(b * b, axis=0))[None, :]
    return qr, np.concatenate(tails, axis=0)

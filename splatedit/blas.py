"""BLAS threading: code that runs its own worker threads keeps the BLAS
library (OpenBLAS in numpy/scipy wheels) on one thread while they run.

Measured (docs/PERFORMANCE.md, "5M-splat support"): the RBF evaluation's two
Python threads plus OpenBLAS's own threads made a 1M-support basis 4.5-9x
slower on the 2-core machine than with one BLAS thread.

The limit is process-wide (a BLAS library has one setting), so it is
reference-counted: the first entry sets it, the last exit restores the
library's own setting, whatever the order in which threads leave.
"""

from __future__ import annotations

import threading
from contextlib import contextmanager
from typing import Iterator

_lock = threading.Lock()
_users = 0
_limiter = None     # the threadpoolctl limiter while _users > 0
_controller = None  # threadpoolctl.ThreadpoolController, made on first use


@contextmanager
def single_blas_thread() -> Iterator[None]:
    """Run the block with BLAS limited to one thread (nesting and threads allowed)."""
    global _users, _limiter, _controller
    with _lock:
        if _users == 0:
            if _controller is None:
                from threadpoolctl import ThreadpoolController
                _controller = ThreadpoolController()
            _limiter = _controller.limit(limits=1, user_api="blas")
        _users += 1
    try:
        yield
    finally:
        with _lock:
            _users -= 1
            if _users == 0 and _limiter is not None:
                _limiter.restore_original_limits()
                _limiter = None


def blas_threads() -> int:
    """The BLAS library's current thread count (1 when none is loaded)."""
    from threadpoolctl import threadpool_info
    counts = [info["num_threads"] for info in threadpool_info() if info.get("user_api") == "blas"]
    return max(counts) if counts else 1

"""Progress reporting for long work (loading, estimating, fitting, saving).

Long-running functions take an optional ``progress`` callback
``progress(stage: str, fraction: float)`` with ``fraction`` in [0, 1].  The CLI
shows it on stderr; the editor shows it in its panel from a worker thread.
Callbacks must be cheap; callers report at most a few hundred times per stage.
"""

from __future__ import annotations

from typing import Callable, Optional

ProgressFn = Callable[[str, float], None]


def report(progress: Optional[ProgressFn], stage: str, fraction: float) -> None:
    """Call ``progress`` if given, clamping ``fraction`` to [0, 1]."""
    if progress is not None:
        progress(stage, min(1.0, max(0.0, float(fraction))))

"""Revision counters: cache keys that are never reused.

``id()`` of an object is reused once the object is freed, so a cache keyed by
it can hand out a stale entry for a new cloud or basis.  :func:`of` gives an
object a revision number from one process-wide, monotonically increasing
counter the first time it is asked (stored on the object), and returns the
same number afterwards: two different objects never share one, even when one
was freed and the other took its address.  A document's own counters (its
selection version) are plain ints that only grow.
"""

from __future__ import annotations

import itertools
import threading

_counter = itertools.count(1)
_lock = threading.Lock()
_ATTR = "_splatedit_revision"


def next_revision() -> int:
    """A fresh revision number (> every number handed out before)."""
    with _lock:
        return next(_counter)


def of(obj) -> int:
    """The revision number of ``obj`` (0 for None): assigned on first use,
    stable for the object's lifetime, never shared with another object."""
    if obj is None:
        return 0
    rev = getattr(obj, _ATTR, None)
    if rev is None:
        with _lock:
            rev = getattr(obj, _ATTR, None)
            if rev is None:
                rev = next(_counter)
                object.__setattr__(obj, _ATTR, rev)
    return rev

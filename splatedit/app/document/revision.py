"""Revision counters: cache keys that are never reused.

``id()`` of an object is reused once the object is freed, so a cache keyed by
it can hand out a stale entry for a new cloud or basis.  :func:`of` gives an
object a revision number from one process-wide, monotonically increasing
counter the first time it is asked (stored on the object), and returns the
same number afterwards: two different objects never share one, even when one
was freed and the other took its address.  A document's own counters (its
selection version) are plain ints that only grow.

The number is stored on the object together with a weak reference to the
object itself (its ``id`` where it cannot be weakly referenced), so that a
shallow copy (``copy.copy``, which carries the instance's ``__dict__`` along:
:meth:`DeformationBasis.apply` makes the deformed cloud that way) is
recognised as another object and gets a number of its own.  Before this, a
committed cloud shared its base cloud's revision, so after an undo the fit
scheduler took the basis fitted on the deformed cloud for the restored one
and the next move carried the undone move along (issue 19, item 2).
"""

from __future__ import annotations

import itertools
import threading
import weakref

_counter = itertools.count(1)
_lock = threading.Lock()
_ATTR = "_splatedit_revision"


def next_revision() -> int:
    """A fresh revision number (> every number handed out before)."""
    with _lock:
        return next(_counter)


def _owner(obj):
    """What identifies ``obj`` itself in its stored revision: a weak
    reference (a copy's points at the original), else its ``id``."""
    try:
        return weakref.ref(obj)
    except TypeError:
        return id(obj)


def _mine(stored, obj) -> bool:
    """``stored`` (rev, owner) was given to ``obj`` itself, not to the object it was copied from."""
    owner = stored[1]
    return owner() is obj if isinstance(owner, weakref.ref) else owner == id(obj)


def of(obj) -> int:
    """The revision number of ``obj`` (0 for None): assigned on first use,
    stable for the object's lifetime, never shared with another object (a
    copy of it included)."""
    if obj is None:
        return 0
    got = getattr(obj, _ATTR, None)
    if got is not None and _mine(got, obj):
        return got[0]
    with _lock:
        got = getattr(obj, _ATTR, None)
        if got is None or not _mine(got, obj):
            got = (next(_counter), _owner(obj))
            object.__setattr__(obj, _ATTR, got)
    return got[0]

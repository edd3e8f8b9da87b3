"""Selection: support and handle masks and their paint rules (paper Sect. 3)."""

import numpy as np

from splatedit.select.selection import HANDLE, SUPPORT, Selection


def test_selection_rules():
    sel = Selection(10)
    assert sel.paint([1, 2, 3, 4], SUPPORT)
    assert sel.paint([4, 5], HANDLE)          # 5 is outside the support
    assert np.flatnonzero(sel.handle).tolist() == [4]
    assert not sel.paint([4], HANDLE)
    sel.paint([3, 4], SUPPORT, erase=True)     # erasing support erases the handle there
    assert np.flatnonzero(sel.support).tolist() == [1, 2]
    assert not sel.handle.any()
    sel.paint([1], HANDLE)
    sel.paint([1], HANDLE, erase=True)
    assert not sel.handle.any() and sel.support[1]
    k = sel.key()
    assert sel.clear()
    assert sel.counts == (0, 0) and sel.key() != k


def test_strokes_are_remembered_per_target_erase_marks_and_reach():
    """Painting widens the target's reach (the painted splats and the dab's
    extra reach) and clears erase marks; erasing marks; a handle's memory is
    its own; copies and snapshots carry it; a selection made from masks has
    no reach limit (None)."""
    s = Selection(10)
    s.paint([1, 2, 3, 4], SUPPORT, reach=[5])
    assert s.reach.tolist() == [False, True, True, True, True, True, False, False, False, False]
    s.paint([2, 3], SUPPORT, erase=True)
    assert s.erased[[2, 3]].all() and s.erased.sum() == 2
    s.paint([3], SUPPORT)
    assert s.erased.tolist().count(True) == 1 and s.erased[2]
    s.paint([1, 4], HANDLE)
    s.paint([4], HANDLE, erase=True)
    assert s.handle_erased[0][4] and not s.erased[4] and s.handle_reach[0][[1, 4]].all()
    c = Selection(10, s.support, handles=s.handles)
    assert c.reach is None and c.handle_reach == [None]
    c.set_memory(s.memory())
    assert np.array_equal(c.erased, s.erased) and np.array_equal(c.handle_erased[0], s.handle_erased[0])
    assert np.array_equal(s.copy().reach, s.reach)
    assert s.add_handle() and len(s.closure_limits()["handle_reach"]) == 2
    s.clear()
    assert not s.erased.any() and not s.reach.any() and len(s.handle_erased) == 1

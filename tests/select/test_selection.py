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

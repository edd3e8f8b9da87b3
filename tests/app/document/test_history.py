"""Undo/redo snapshots."""

import numpy as np

from splatedit.app.document.history import History, Snapshot
from splatedit.model import SplatCloud


def cloud(n=8, off=0.0):
    rng = np.random.default_rng(1)
    p = rng.normal(size=(n, 3)) + off
    return SplatCloud(p, np.tile([0.01, 0, 0], (n, 1)), np.tile([0, 0.01, 0], (n, 1)))


def test_undo_redo_and_dirty():
    c0, c1 = cloud(), cloud(off=1)
    s = np.zeros(8, bool)
    h = History()
    h.reset(Snapshot.make(c0, s, s))
    assert not h.geometry_dirty and not h.can_undo
    s1 = s.copy(); s1[:3] = True
    h.push(Snapshot.make(c0, s1, s))
    assert not h.geometry_dirty           # selection only
    h.push(Snapshot.make(c1, s1, s, edits=("e",)))
    assert h.geometry_dirty
    snap = h.undo()
    assert snap.cloud is c0 and snap.masks()[0][:3].all() and not h.geometry_dirty
    snap = h.redo()
    assert snap.cloud is c1 and snap.edits == ("e",)
    h.mark_saved()
    assert not h.geometry_dirty
    h.undo()
    assert h.geometry_dirty
    h.push(Snapshot.make(c0, s, s))       # drops the redo tail (and the saved state)
    assert not h.can_redo and h.geometry_dirty


def test_memory_cap_drops_oldest():
    s = np.zeros(8, bool)
    h = History(max_bytes=3 * 8 * 3 * 8 * 2 + 100)
    h.reset(Snapshot.make(cloud(), s, s))
    for i in range(5):
        h.push(Snapshot.make(cloud(off=i + 1), s, s))
    assert len(h) <= 3
    assert h.current.cloud is not None
    while h.undo():
        pass
    assert not h.can_undo

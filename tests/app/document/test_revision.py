"""Revision numbers never repeat, even when a freed object's id() is reused."""

from __future__ import annotations

import gc

from splatedit.app.document import revision
import numpy as np

from splatedit.model.cloud import SplatCloud


def plane_cloud():
    p = np.random.default_rng(0).normal(size=(8, 3))
    return SplatCloud(p, np.tile([0.01, 0, 0], (8, 1)), np.tile([0, 0.01, 0], (8, 1)), None)


def test_a_new_object_at_a_freed_address_gets_a_new_revision():
    seen_ids, revs = {}, set()
    reused = False
    for _ in range(200):
        c = plane_cloud()
        r = revision.of(c)
        assert revision.of(c) == r                   # stable for the object's lifetime
        assert r not in revs                         # never handed out twice
        revs.add(r)
        reused |= id(c) in seen_ids                  # the case id() keys got wrong
        seen_ids[id(c)] = r
        del c
        if len(revs) % 50 == 0:
            gc.collect()
    assert reused, "CPython did not reuse an address in 200 tries: the test proves nothing"


def test_revisions_increase_and_none_is_zero():
    a, b = plane_cloud(), plane_cloud()
    assert revision.of(None) == 0
    ra, rb = revision.of(a), revision.of(b)
    assert 0 < ra < rb < revision.next_revision()


def test_a_shallow_copy_gets_its_own_revision_not_its_originals():
    """``copy.copy`` carries the stored number along in ``__dict__`` (the
    committed cloud of an edit is made that way): the copy must still be
    another revision, else caches keyed by it (the fitted basis) hand the
    copy's entry to the original (issue 19 item 2: undo then rotate)."""
    import copy
    a = plane_cloud()
    ra = revision.of(a)
    b = copy.copy(a)
    rb = revision.of(b)
    assert rb != ra and revision.of(a) == ra and revision.of(b) == rb
    c = copy.copy(b)                  # a copy of a copy, also after the original is gone
    del a
    gc.collect()
    assert revision.of(c) not in (ra, rb)

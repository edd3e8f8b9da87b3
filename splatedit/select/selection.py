"""The editor's selection: one support mask and one or more disjoint handle
masks inside it (the paper's Sect. 3: the *support* (blue) is painted first,
then one or more disjoint *handles* (green; the active one brighter) inside
it; a handle splat is always a support splat, erasing support erases the
handles there too).  Pure numpy; the brush (:mod:`splatedit.app.tools.pick_brush`) and
the selection tools paint through :meth:`Selection.paint`.

The selection also remembers what the user's strokes said beyond the masks,
for the closure (:mod:`splatedit.select.closure`), per target (the support
and each handle):

* *reach*: the splats the strokes covered (the painted ones, plus what the
  brush passed over on screen at any depth, see :meth:`Selection.paint`'s
  ``reach``): closure adds splats only there.  A selection made from masks
  (not painted) has no reach (None): closure is not limited;
* *erased*: the splats erase strokes (or tools that removed splats) took
  out: closure never adds them again; painting a splat clears its mark.
"""

from __future__ import annotations

import numpy as np

#: brush targets
SUPPORT = "support"
HANDLE = "handle"


class Selection:
    """Support mask plus one or more handle masks, with the paint/erase rules.

    Several handles (paper Sect. 3: "one or more handles") are pairwise
    disjoint masks inside the support; one of them is *active*: the handle
    brush paints into it (only splats of the support that belong to no other
    handle) and the manipulator moves it.  ``handle`` is the active handle's
    mask; ``any_handle`` the union.  There is always at least one (possibly
    empty) handle.
    """

    def __init__(self, n: int, support: np.ndarray | None = None, handle: np.ndarray | None = None,
                 *, handles=None, active: int = 0):
        self.n = int(n)
        self.support = np.zeros(n, bool) if support is None else np.asarray(support, bool).copy()
        if handles is None:
            handles = [handle] if handle is not None else []
        self.handles: list[np.ndarray] = []
        taken = np.zeros(self.n, bool)
        for h in handles:
            m = np.asarray(h, bool).copy() & self.support & ~taken
            taken |= m
            self.handles.append(m)
        if not self.handles:
            self.handles.append(np.zeros(self.n, bool))
        self.active = int(min(max(active, 0), len(self.handles) - 1))
        #: (n,) bool: the support's reach (None: not painted, no limit) and
        #: erased splats (see the module docstring)
        self.reach = None if support is not None else np.zeros(self.n, bool)
        self.erased = np.zeros(self.n, bool)
        #: per handle, the same (lists aligned with ``handles``)
        self.handle_reach = [None if support is not None else np.zeros(self.n, bool) for _ in self.handles]
        self.handle_erased = [np.zeros(self.n, bool) for _ in self.handles]

    def copy(self) -> "Selection":
        out = Selection(self.n, self.support, handles=self.handles, active=self.active)
        out.set_memory(self.memory())
        return out

    # ---------------------------------------------------------------- memory
    def memory(self) -> tuple:
        """The stroke memory as bit-packed bytes (reach, erased, then per
        handle reach and erased; b"" for a reach of None), for undo snapshots."""
        self._aligned()
        masks = [self.reach, self.erased]
        for r, e in zip(self.handle_reach, self.handle_erased):
            masks += [r, e]
        return tuple(b"" if m is None else np.packbits(m).tobytes() for m in masks)

    def set_memory(self, packed: tuple) -> None:
        """Restore :meth:`memory`'s bytes (an empty tuple keeps the defaults)."""
        if not packed:
            return
        m = [None if not b else np.unpackbits(np.frombuffer(b, np.uint8), count=self.n).astype(bool)
             for b in packed]
        self.reach, self.erased = m[0], m[1]
        k = len(self.handles)
        self.handle_reach = [m[2 + 2 * i] if 3 + 2 * i < len(m) else None for i in range(k)]
        self.handle_erased = [m[3 + 2 * i] if 3 + 2 * i < len(m) else np.zeros(self.n, bool) for i in range(k)]

    def _aligned(self) -> None:
        """Keep the per-handle memory lists as long as ``handles`` (code that
        replaces ``handles`` wholesale keeps the count; this guards the rest:
        a new handle has no reach limit yet, nothing erased)."""
        k = len(self.handles)
        self.handle_reach = (self.handle_reach + [None] * k)[:k]
        self.handle_erased = (self.handle_erased + [np.zeros(self.n, bool) for _ in range(k)])[:k]

    def closure_limits(self) -> dict:
        """Keyword arguments of :func:`~splatedit.select.closure.close_selection`
        that keep the user's strokes: reach and erased marks of the support and
        of every handle."""
        self._aligned()
        return dict(reach=self.reach, erased=self.erased, handle_reach=list(self.handle_reach),
                    handle_erased=list(self.handle_erased))

    def _memory_of(self, target: str) -> tuple[np.ndarray | None, np.ndarray]:
        self._aligned()
        if target == SUPPORT:
            return self.reach, self.erased
        return self.handle_reach[self.active], self.handle_erased[self.active]

    def remember(self, target: str, painted=None, erased=None, reach=None) -> None:
        """Record a stroke of ``target`` (support or the active handle):
        ``painted`` indices leave the erased marks and join the reach, as do
        ``reach`` indices (what the stroke covered); ``erased`` indices are
        marked erased."""
        r, e = self._memory_of(target)
        for idx in (painted, reach):
            if idx is not None and r is not None:      # None: no limit to widen
                r[np.asarray(idx, np.int64)] = True
        if painted is not None:
            e[np.asarray(painted, np.int64)] = False
        if erased is not None:
            e[np.asarray(erased, np.int64)] = True

    @property
    def handle(self) -> np.ndarray:
        """The active handle's mask (painted and moved in place)."""
        return self.handles[self.active]

    @property
    def any_handle(self) -> np.ndarray:
        """Union of all handles."""
        out = np.zeros(self.n, bool)
        for h in self.handles:
            out |= h
        return out

    def others(self) -> np.ndarray:
        """Union of the inactive handles."""
        out = np.zeros(self.n, bool)
        for i, h in enumerate(self.handles):
            if i != self.active:
                out |= h
        return out

    def handle_of(self, i: int) -> int:
        """Index of the handle containing splat ``i``, or -1."""
        for k, h in enumerate(self.handles):
            if h[i]:
                return k
        return -1

    def nonempty(self) -> list[int]:
        """Indices of the handles that select at least one splat (the fitted ones)."""
        return [k for k, h in enumerate(self.handles) if h.any()]

    # --------------------------------------------------------------- handles
    def add_handle(self) -> bool:
        """Start a new (empty) handle and make it active; an empty active
        handle is reused (False: nothing changed)."""
        if not self.handle.any():
            return False
        self.handles.append(np.zeros(self.n, bool))
        self.handle_reach.append(np.zeros(self.n, bool))
        self.handle_erased.append(np.zeros(self.n, bool))
        self.active = len(self.handles) - 1
        return True

    def remove_handle(self, i: int | None = None) -> bool:
        """Remove handle ``i`` (default: the active one); one empty handle
        remains when the last one is removed."""
        i = self.active if i is None else int(i)
        if len(self.handles) == 1:
            changed = bool(self.handles[0].any())
            self.handles[0][:] = False
            self.handle_reach[0] = np.zeros(self.n, bool)
            self.handle_erased[0][:] = False
            return changed
        del self.handles[i]
        del self.handle_reach[i]
        del self.handle_erased[i]
        if self.active >= i and self.active > 0:
            self.active -= 1
        return True

    def select_handle(self, i: int) -> bool:
        i = int(i) % len(self.handles)
        changed = i != self.active
        self.active = i
        return changed

    # ---------------------------------------------------------------- paint
    def paint(self, indices: np.ndarray, target: str, erase: bool = False, reach=None) -> bool:
        """Add (or with ``erase`` remove) ``indices`` to the support or the
        active handle, and remember it (painted splats join the target's
        reach and lose their erased mark; erased ones are marked).

        Painting a handle only takes support splats that belong to no other
        handle; erasing it only clears the active handle; erasing the support
        clears every handle there.  ``reach``: indices the stroke covered
        beyond the painted ones (the brush circle's splats at any depth),
        added to the target's reach when painting.  Returns True when a mask
        changed.
        """
        idx = np.asarray(indices, np.int64)
        if erase:
            self.remember(target, erased=idx)
        else:
            self.remember(target, painted=idx, reach=reach)
        if len(idx) == 0:
            return False
        before_s = self.support[idx].copy()
        before_h = [h[idx].copy() for h in self.handles]
        if target == SUPPORT:
            if erase:
                self.support[idx] = False
                for h in self.handles:
                    h[idx] = False
            else:
                self.support[idx] = True
        elif target == HANDLE:
            h = self.handle
            if erase:
                h[idx] = False
            else:
                h[idx] |= self.support[idx] & ~self.others()[idx]
        else:
            raise ValueError(f"unknown brush target {target!r}")
        return bool((before_s != self.support[idx]).any()
                    or any((b != h[idx]).any() for b, h in zip(before_h, self.handles)))

    def clear(self, target: str | None = None) -> bool:
        """Clear the handles (target HANDLE: one empty handle remains) or
        everything (None/SUPPORT)."""
        changed = bool(self.any_handle.any()) or len(self.handles) > 1 or \
            (target != HANDLE and bool(self.support.any()))
        self.handles = [np.zeros(self.n, bool)]
        self.handle_reach = [np.zeros(self.n, bool)]
        self.handle_erased = [np.zeros(self.n, bool)]
        self.active = 0
        if target != HANDLE:
            self.support[:] = False
            self.reach = np.zeros(self.n, bool)
            self.erased = np.zeros(self.n, bool)
        return changed

    @property
    def counts(self) -> tuple[int, int]:
        """(support splats, handle splats of all handles)."""
        return int(self.support.sum()), int(sum(int(h.sum()) for h in self.handles))

    def key(self) -> tuple:
        """Hashable content key of what the fit depends on (support and the
        non-empty handles, in order)."""
        return (self.n, np.packbits(self.support).tobytes(),
                tuple(np.packbits(self.handles[k]).tobytes() for k in self.nonempty()))

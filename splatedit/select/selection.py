"""The editor's selection: one support mask and one or more disjoint handle
masks inside it (the paper's Sect. 3: the *support* (blue) is painted first,
then one or more disjoint *handles* (green; the active one brighter) inside
it; a handle splat is always a support splat, erasing support erases the
handles there too).  Pure numpy; the brush (:mod:`splatedit.app.brush`) and
the selection tools paint through :meth:`Selection.paint`.
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

    def copy(self) -> "Selection":
        return Selection(self.n, self.support, handles=self.handles, active=self.active)

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
        self.active = len(self.handles) - 1
        return True

    def remove_handle(self, i: int | None = None) -> bool:
        """Remove handle ``i`` (default: the active one); one empty handle
        remains when the last one is removed."""
        i = self.active if i is None else int(i)
        if len(self.handles) == 1:
            changed = bool(self.handles[0].any())
            self.handles[0][:] = False
            return changed
        del self.handles[i]
        if self.active >= i and self.active > 0:
            self.active -= 1
        return True

    def select_handle(self, i: int) -> bool:
        i = int(i) % len(self.handles)
        changed = i != self.active
        self.active = i
        return changed

    # ---------------------------------------------------------------- paint
    def paint(self, indices: np.ndarray, target: str, erase: bool = False) -> bool:
        """Add (or with ``erase`` remove) ``indices`` to the support or the
        active handle.

        Painting a handle only takes support splats that belong to no other
        handle; erasing it only clears the active handle; erasing the support
        clears every handle there.  Returns True when a mask changed.
        """
        idx = np.asarray(indices, np.int64)
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
        self.active = 0
        if target != HANDLE:
            self.support[:] = False
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

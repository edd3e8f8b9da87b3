"""Undo/redo of editor states.

The editor's document state is small and immutable-by-convention: the base
cloud (a :class:`SplatCloud` never modified in place), the support and handle
masks (several handles, one active), the session's rig (control-curve points
and the pending pose: per-handle matrices and curve-point moves) and the list
of committed edits.  :class:`History` keeps snapshots of
those: ``push`` after every user action (a brush stroke, a clear, a commit),
``undo``/``redo`` move along the list.  Clouds are shared between snapshots
until an edit replaces them, so a selection step costs two bit-packed masks;
a committed edit costs one cloud.  ``max_bytes`` bounds the memory held by
old snapshots (the oldest are dropped first; the current one is always kept).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from splatedit.app.document import revision


@dataclass(frozen=True)
class Snapshot:
    cloud: object                 # SplatCloud
    support: bytes                # np.packbits of the (n,) bool mask
    handle: bytes                 # the active handle
    edits: tuple = ()             # committed script Edits, in order
    label: str = ""
    n: int = 0
    handles: tuple = ()           # every handle (packbits), in order
    active: int = 0               # index of the active handle
    rig: tuple = ()               # session state beyond the masks (curve, pending pose)
    memory: tuple = ()            # the selection's stroke memory (Selection.memory: packbits)

    @staticmethod
    def make(cloud, support: np.ndarray, handle, edits=(), label: str = "", *, active: int = 0,
             rig: tuple = (), memory: tuple = ()) -> "Snapshot":
        """``handle``: one mask or a list of masks (``active`` picks the active one)."""
        hs = [handle] if isinstance(handle, np.ndarray) else list(handle)
        packed = tuple(np.packbits(h).tobytes() for h in hs)
        return Snapshot(cloud, np.packbits(support).tobytes(), packed[active], tuple(edits), label,
                        len(support), packed, active, tuple(rig), tuple(memory))

    def _unpack(self, b: bytes) -> np.ndarray:
        return np.unpackbits(np.frombuffer(b, np.uint8), count=self.n).astype(bool)

    def masks(self) -> tuple[np.ndarray, np.ndarray]:
        """(support, active handle)."""
        return self._unpack(self.support), self._unpack(self.handle)

    def handle_masks(self) -> list[np.ndarray]:
        return [self._unpack(b) for b in (self.handles or (self.handle,))]


def _cloud_bytes(cloud) -> int:
    from splatedit.app.document.gaussian import document_bytes
    return int(sum(getattr(cloud, a).nbytes for a in ("positions", "u", "v"))) + document_bytes(cloud)


@dataclass
class History:
    max_bytes: int = 2 << 30
    _states: list = field(default_factory=list)
    _pos: int = -1
    saved_pos: int = 0

    def reset(self, snap: Snapshot) -> None:
        self._states = [snap]
        self._pos = 0
        self.saved_pos = 0

    @property
    def current(self) -> Snapshot:
        return self._states[self._pos]

    def push(self, snap: Snapshot) -> None:
        """Record a new state after the current one (drops the redo tail)."""
        del self._states[self._pos + 1:]
        if self.saved_pos > self._pos:
            self.saved_pos = -1
        self._states.append(snap)
        self._pos += 1
        self._trim()

    def _trim(self) -> None:
        while len(self._states) > 1 and self._memory() > self.max_bytes and self._pos > 0:
            self._states.pop(0)
            self._pos -= 1
            self.saved_pos -= 1

    def _memory(self) -> int:
        seen, total = set(), 0
        for s in self._states:
            if revision.of(s.cloud) not in seen:
                seen.add(revision.of(s.cloud))
                total += _cloud_bytes(s.cloud)
            total += len(s.support) + sum(len(b) for b in s.handles) + sum(len(b) for b in s.memory)
        return total

    @property
    def can_undo(self) -> bool:
        return self._pos > 0

    @property
    def can_redo(self) -> bool:
        return self._pos + 1 < len(self._states)

    def undo(self) -> Snapshot | None:
        if not self.can_undo:
            return None
        self._pos -= 1
        return self.current

    def redo(self) -> Snapshot | None:
        if not self.can_redo:
            return None
        self._pos += 1
        return self.current

    @property
    def labels(self) -> list[str]:
        """The label of every kept state, oldest first (index = :attr:`position`)."""
        return [s.label for s in self._states]

    @property
    def position(self) -> int:
        return self._pos

    def mark_saved(self, position: int | None = None) -> None:
        """Remember the current state (or the one at ``position``, as returned
        by :attr:`position` when a background save started) as saved."""
        self.saved_pos = self._pos if position is None else position

    @property
    def geometry_dirty(self) -> bool:
        """True when the current cloud differs from the last saved (or loaded) one."""
        if 0 <= self.saved_pos < len(self._states):
            return self._states[self.saved_pos].cloud is not self.current.cloud
        return True

    def __len__(self) -> int:
        return len(self._states)

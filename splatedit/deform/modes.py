"""How a fitted basis turns handle transforms into splat motion.

``LINEAR``   the paper's deformation: every handle's affine map is interpolated
             linearly by the triharmonic RBF (exact for translations; large
             rotations shrink the shape, the classic limit of linear methods).
``ROTATION`` rotation-aware: each handle's rotation (polar decomposition of its
             map) is blended over the support with the smooth weight field of
             the fit, the RBF carries the remaining stretch and translation.
``DETAIL``   detail-preserving: the support is a smooth base surface plus normal
             offsets; the base is deformed (rotation-aware) and the offsets are
             re-attached along the deformed normals (paper Sect. 8).
"""

from __future__ import annotations

from enum import Enum


class DeformationMode(str, Enum):
    """The deformation model of an edit (script key ``"deformation"``)."""

    LINEAR = "linear"
    ROTATION = "rotation"
    DETAIL = "detail"

    @classmethod
    def parse(cls, text: str) -> "DeformationMode":
        """The mode named ``text`` (case-insensitive); ValueError lists the names."""
        try:
            return cls(str(text).strip().lower())
        except ValueError:
            names = ", ".join(repr(m.value) for m in cls)
            raise ValueError(f"unknown deformation mode {text!r} (expected one of {names})") from None

"""splatedit.deform: the triharmonic RBF space deformation (pure numpy/scipy, no GPU).

kernels and centres -> :class:`TriharmonicRBF` (exact LU or incremental QR) ->
constraints from a selection (bands, handles, curves) -> :class:`DeformationBasis`
(B, Bx, By, Bz so that p' = p + B dC).
"""

from splatedit.deform import transform
from splatedit.deform.basis import DeformationBasis
from splatedit.deform.centers import farthest_point_order
from splatedit.deform.constraints import Constraints, ConstraintGroup, build_constraints
from splatedit.deform.curves import ControlCurve
from splatedit.deform.rbf import TriharmonicRBF

__all__ = ["ConstraintGroup", "Constraints", "ControlCurve", "DeformationBasis", "TriharmonicRBF",
           "build_constraints", "farthest_point_order", "transform"]

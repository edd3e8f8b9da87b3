"""splatedit.deform"""

from splatedit.deform.centers import farthest_point_order
from splatedit.deform.rbf import TriharmonicRBF

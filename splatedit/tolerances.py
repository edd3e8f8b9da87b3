"""Every numeric tolerance and tuning constant of splatedit, in one place.

Units: lengths are in model units unless the name says ``_PX`` (pixels) or
``_REL`` (relative to the model's bounding-box diagonal).
"""

# --- splat model validation ---------------------------------------------
#: smallest allowed tangent-axis length, relative to the bounding-box diagonal
MIN_AXIS_LENGTH_REL = 1e-9
#: |u x v| / (|u| |v|) below this means u and v are (nearly) parallel
MIN_AXIS_SINE = 1e-6

# --- normal and splat-size estimation ----------------------------------
#: neighbours for PCA normals (Hoppe et al. 1992 use a k-neighbourhood)
NORMAL_NEIGHBOURS = 16
#: neighbours for the MST orientation graph
ORIENT_NEIGHBOURS = 8
#: splat radius = this factor * distance to the SPACING_NEIGHBOUR-th neighbour
SPLAT_RADIUS_FACTOR = 1.0
SPACING_NEIGHBOUR = 6

# --- RBF fitting --------------------------------------------------------
#: the paper's relative L2 tolerance for the incremental QR (Sect. 5 and 8)
IQR_DEFAULT_TOL = 1e-7
#: method="auto" uses the exact dense solve up to this many constraints
AUTO_EXACT_MAX_CONSTRAINTS = 3000
#: columns per blocked Householder panel in the incremental QR
IQR_PANEL_COLUMNS = 128
#: rows of evaluation points per chunk (bounds memory of Phi_N to
#: EVAL_CHUNK_ROWS * n_centers * 8 bytes)
EVAL_CHUNK_ROWS = 8192
#: relative singular-value cutoff that declares the polynomial block rank
#: deficient (constraints on a quadric)
POLY_RANK_RTOL = 1e-9

# --- constraints --------------------------------------------------------
#: thickness of the fixed and handle bands, in point spacings ("three rings")
BAND_RINGS = 3.0

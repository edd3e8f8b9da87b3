"""Tolerances and tuning constants of reading and writing files, hostile inputs, georeferenced origins (splatedit.io, info).

Part of :mod:`splatedit.tolerances` (import them from there); every value
carries the measurement behind it.
"""


# --- file input ---------------------------------------------------------
#: text files (XYZ, OFF) are tokenised in blocks of about this many bytes
TEXT_BLOCK_BYTES = 1 << 24


# --- hostile inputs (issue 12) ----------------------------------------------
#: largest |value| of a coordinate, normal component, radius or splat axis
#: accepted from a file or in a SplatCloud.  Coordinates near 1e155 made the
#: k-d tree's squared distances overflow (IndexError in normal estimation) and
#: a radius of 1e160 gave NaN normals (|u x v| = 1e320); the fitting code takes
#: up to 4th powers of coordinates (1e60 here, far inside float64).  1e15 is
#: the float64 limit of a unit step (53-bit mantissa: 2^53 = 9.0e15), i.e.
#: 1e9 km in millimetres: no real scan comes near it
MAX_COORDINATE_ABS = 1e15
#: largest edit script read (bytes).  The demo script is 0.6 kB and a curve of
#: 10,000 picked points about 0.5 MB; a larger file is not a script (and
#: reading stops there instead of filling the memory from /dev/zero)
MAX_SCRIPT_BYTES = 16 * 2**20
#: a curve may have at most max(number of splats, this) samples (given or one
#: per point spacing).  Kept samples are over free splats at least a spacing
#: apart, so more than one per splat adds nothing; "samples": 10000000 ran 37 s
#: into a MemoryError and a curve point at 1e9 asked for 1.25 TiB.  The floor
#: keeps curves over small test clouds (a few hundred splats) legal
CURVE_MAX_SAMPLES_FLOOR = 1024
#: Camera.frame: smallest bounding-sphere radius framed, relative to the
#: largest coordinate of the box centre (a single point with no splat size
#: given).  Replaces an absolute 1e-9 that framed a bunny scaled by 1e-10 as a
#: dot (coverage 0.004 of the image instead of 0.235); 1e-12 is, like
#: RENDER_CLIP_MIN_RADIUS_REL, 4500 float64 ulps: eye and centre stay distinct
RENDER_FRAME_MIN_RADIUS_REL = 1e-12
#: peak memory of `splatedit render` per image pixel (bytes), without and with
#: --buffers.  Measured (bunny, lavapipe, peak RSS minus the 64x64 run's
#: 183 MB): 2048x2048 takes 35 B/px, with --buffers 147 B/px; issue 12 saw
#: 8.6 GB for 16384x16384 (32 B/px) and 9.2 GB for 8192x8192 --buffers
#: (137 B/px).  A larger image than MemAvailable allows is refused up front
RENDER_BYTES_PER_PIXEL = 36
RENDER_BUFFERS_BYTES_PER_PIXEL = 150
#: a PLY header whose counts need more than this many bytes beyond the file's
#: size is refused before parsing (400,000,000 declared faces in a 188-byte
#: file took 26 s and 3.2 GB to fail; now 0.4 s, 68 MB).  Smaller shortfalls
#: go to the parser, which names the row where the data end (plyfile
#: allocates the declared rows first: 1 MiB of rows is harmless)
PLY_DECLARED_EXCESS_BYTES = 2**20


# --- scan-scale I/O (issue 11, parts 1-3) -------------------------------------
#: SplatCloud.validate tests axes this many rows at a time (at most an
#: eighth of the cloud): its temporaries (lengths, dot products) stay ~50 MB
#: instead of several 240 MB arrays at 10M splats.  With whole-array
#: temporaries and the normals kept, a 10M read peaked at 1.57x the arrays
#: kept; now 1.15x (splatedit bench io --large)
VALIDATE_CHUNK_ROWS = 1 << 20
#: binary PLY bodies are read through a buffer of this many bytes (at most
#: an eighth of the file) and converted chunk by chunk: 10M splats (840 MB)
#: then need the arrays kept plus 32 MB, not a second full copy; the PLY
#: writer converts the same amount at a time.  Reading the 10M body's
#: copies through this buffer or through mmap took the same 0.7-0.9 s
PLY_READ_CHUNK_BYTES = 32 * 2**20
#: a file whose bounding box reaches farther from 0 than this (model units)
#: is rebased to a local origin on load.  float32 (GPU) has a step of
#: |x| * 2^-24: 0.6 mm at 1e4 m, 0.03 m at UTM x = 500,000, 0.5 m at
#: y = 5,000,000.  Below 1e4 nothing changes (all our sample models)
REBASE_MIN_ABS = 1e4
#: `splatedit info` computes spacing, outliers and boundary splats exactly up
#: to this many splats (the issue's 36 s of k-NN at 10M scale to about 4 s at
#: 1M, not measured again here); above it, from spatial patches
#: (splatedit.model.sample) of about INFO_SAMPLE_POINTS points.  At 10M the
#: all-points kNN took 36 s of the issue's 47 s
INFO_EXACT_MAX_POINTS = 1_000_000
INFO_SAMPLE_POINTS = 100_000
#: patch cells are this many rough spacings wide.  The rough spacing is the
#: median nearest-neighbour distance of a random subsample scaled to the full
#: density as for random points on a surface; a regular scan's spacing is up
#: to 2.3x that (a 10M Fibonacci sphere: 0.00053 against 1.08e-3), so cells
#: are 28-64 true spacings wide.  At 32 only 6 % of the patch points of that
#: sphere were far enough from the faces; at 64, 40-60 %
INFO_PATCH_SPACINGS = 64.0
#: figures are taken at patch points at least this quantile of the k-th
#: neighbour distances found from their cell's faces (0.99 let the few
#: corner points, whose one-sided neighbourhoods are wide, set the margin)
INFO_PATCH_REACH_QUANTILE = 0.95
#: LAS/LAZ written from a cloud not read from LAS: coordinate resolution
#: (model units; millimetres for metre scans, the usual LiDAR grid)
LAS_DEFAULT_SCALE = 0.001


# --- E57 writing precision (tester) -------------------------------------------------------
# pye57's writer stores points in single precision; splatedit writes local coordinates with the
# origin as the scan pose's translation.  A 100 m UTM tile (x ~ 512,000, y ~ 5,123,000, mm grid)
# written to E57 and read back is within 4e-6 m of the original (float32 step at 50 m from the
# origin); world coordinates in the points themselves were off by up to 0.25 m.
E57_ROUND_TRIP_ATOL = 1e-5


# ---------------------------------------------------------------------------
# Stable local origin of georeferenced models, `info` at scan scale (issues 10, 11: iopolish)
# ---------------------------------------------------------------------------
#: a model far from 0 (beyond REBASE_MIN_ABS) that carries no origin of its
#: own is rebased to its bounding-box centre rounded to a multiple of the
#: largest power of two not above its longest side, and not below this
#: (model units: whole metres for metre scans, as the earlier rounding).
#: Local coordinates then stay within the longest side of 0: a 100 m UTM
#: tile at (512,345, 5,123,456) gets steps of 64 m, origin (512,384,
#: 5,123,520, 320) and local values up to 64 m (float32 rounding error
#: measured 1.9e-6 m, at most 3.8e-6: as with the exact centre)
REBASE_GRID_MIN = 1.0
#: the origin a file carries (PLY comment, LAS offset, E57 pose) is used when
#: the model lies within this many times its longest side of it: at most
#: twice the grid origin's reach (one float32 bit), and far enough that an
#: edit moving the model by a fraction of its size keeps the stored origin
REBASE_STORED_REACH = 2.0


# --- scanner readers against hostile headers (issue 21) -----------------------
#: a LAZ file may declare at most this many points per byte of compressed
#: point data (more is refused before the library allocates for them).
#: Measured with laspy/lazrs 0.8: 200,000 identical points (the best case of
#: the arithmetic coder) take 0.0135 bytes each, 74 points per byte; about 5x
#: that margin.  'LASF' and random bytes made laspy allocate without end
#: (2.7 GB at 120 s) before this bound
LAZ_MAX_POINTS_PER_BYTE = 400
#: smallest |scale| of a LAS file accepted: a scale of 0 collapsed every
#: point onto the offset; below 1e-12 model units (a picometre in metres)
#: 32-bit integers span less than 4.3 mm, no scanner's grid
LAS_MIN_SCALE = 1e-12
#: an E57 scan may declare at most this many points per byte of the whole
#: file before pye57 allocates for them: libE57Format packs each field in at
#: least one bit unless it is constant (then 0 bits: a scan of one repeated
#: point, which no scanner writes); 8 bits per byte
E57_MAX_POINTS_PER_BYTE = 8
#: smallest positive extent (longest bounding-box side, model units) of a
#: model.  Measured on a 400-point unit sphere scaled by 10^-e: at 1e-60 the
#: spacing, splat sizes and boundary count of `info` equal the unit sphere's
#: (scaled); at 1e-80 the boundary count is wrong (72 of 400 instead of 2:
#: squared distances near 1e-160 lose their bits), at 1e-120 the splats
#: come out degenerate, at 1e-300 the render showed rings with exit 0.  1e-50
#: keeps a factor 1e10 from the first failure; all points in one place
#: (extent 0) stay valid
MIN_EXTENT_ABS = 1e-50


# --- COPC and out-of-core scans (issue 23) -----------------------------------
#: points an octree node above the leaves keeps when splatedit lays out a
#: COPC file (a random sample of its subtree): 20k, so that a level-of-detail
#: read of a 100M-point terrain's top levels (a few hundred nodes) is a few
#: million points, and a node decodes in a few ms (lazrs: 200k points in
#: 0.03 s measured)
COPC_NODE_POINTS = 20_000
#: a subtree of at most this many points is one leaf node (3x a node's
#: sample: leaves are not split for a few points)
COPC_LEAF_POINTS = 60_000
#: the deepest level the layout subdivides to (cells are counted there;
#: 2**10 cells a side: 20 cm cells on a 200 m tile)
COPC_FINE_DEPTH = 10
#: out-of-core deform: the box of the script's regions is grown by this
#: fraction of its longest side before the nodes are read (the fit's fixed
#: border ring and the neighbours that size the rim's splats lie there)
COPC_EDIT_MARGIN_REL = 0.25
#: out-of-core render: a node's children are read while its point spacing
#: projects to more than this many pixels (Potree's rule, ~1 px)
COPC_REFINE_PX = 1.0
#: out-of-core render: at most this many points are read and drawn
COPC_RENDER_BUDGET = 3_000_000

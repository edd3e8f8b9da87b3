"""Tolerances and tuning constants of splat arrays, normal / size estimation, orientation, framing extents (splatedit.model).

Part of :mod:`splatedit.tolerances` (import them from there); every value
carries the measurement behind it.
"""


# --- splat model validation ---------------------------------------------
#: smallest allowed tangent-axis length, relative to the bounding-box diagonal
MIN_AXIS_LENGTH_REL = 1e-9
#: ... or, where smaller, relative to this many times the splat's distance
#: from the local origin (issue 21): a scan of unit size with one glitch
#: point 1e9 away has a diagonal of 1e9, and its 0.15-unit splats were
#: refused as degenerate.  Splats farther than diagonal / 8 from the origin
#: keep the diagonal rule (the editor's commit check relies on it: an edit
#: that grows the diagonal still makes far-too-small splats there
#: degenerate); float64 resolves an axis 1e-9 of its centre's magnitude
#: with 7 digits to spare
MIN_AXIS_POSITION_FACTOR = 8.0
#: |u x v| / (|u| |v|) below this means u and v are (nearly) parallel
MIN_AXIS_SINE = 1e-6


# --- normal and splat-size estimation ----------------------------------
#: neighbours for PCA normals (Hoppe et al. 1992 use a k-neighbourhood)
NORMAL_NEIGHBOURS = 16
#: neighbours for the MST orientation graph
ORIENT_NEIGHBOURS = 8
#: splat radius = this factor * distance to the SPACING_NEIGHBOUR-th neighbour.
#: 1.0 leaves pin holes on uniformly random samples (largest empty circles);
#: over 12 random sphere samples (1k-200k points, 200k-2M surface probes) the
#: largest factor any probe needed was 1.30; 1.5 keeps a margin (see
#: splatedit.model.estimate.splat_radii)
SPLAT_RADIUS_FACTOR = 1.5
SPACING_NEIGHBOUR = 6
#: points per chunk of the batched 3x3 covariance / eigen-decomposition
#: (bounds memory to about ESTIMATE_CHUNK_POINTS * NORMAL_NEIGHBOURS * 24 bytes)
ESTIMATE_CHUNK_POINTS = 65536
#: added to the Riemannian-graph weight 1 - |n_i . n_j| so that parallel
#: normals still give a (positive-weight) edge in the sparse MST
ORIENT_WEIGHT_EPS = 1e-9
#: a component's seed normal (at its highest point) with |n_z| below this is
#: oriented away from the component centroid instead of towards +z
ORIENT_SEED_MIN_NZ = 1e-3
#: a k-th-neighbour radius below this fraction of the median radius (duplicate
#: points) is replaced by the median radius
MIN_SPLAT_RADIUS_REL_MEDIAN = 1e-3
#: splat radius used when there are no neighbours at all (a single point or
#: all points identical), model units
FALLBACK_SPLAT_RADIUS = 1.0
#: mesh vertex splat radius = this factor * the longest edge of the incident
#: triangles.  Every point of a triangle lies within L/sqrt(3) of one of its
#: corners (L = longest edge; equality for the equilateral triangle), so
#: 1/sqrt(3) just closes the surface; the 1.2 margin makes neighbouring EWA
#: kernels overlap instead of touching.  See splatedit.model.mesh.
MESH_SPLAT_RADIUS_FACTOR = 1.2 / 3 ** 0.5
#: an area-weighted vertex normal shorter than this times the squared
#: incident edge length (faces cancel or are all degenerate) is replaced by a
#: PCA normal
MESH_NORMAL_MIN_REL = 1e-12


# --- cleaning real scans: robust splat sizes, boundaries, outliers -----------
#: neighbourhood (the point itself included) of the radius cap and of the
#: boundary test; equal to NORMAL_NEIGHBOURS so the normal-estimation query is reused
SIZE_NEIGHBOURS = 16
#: a splat radius is at most this times the median radius of its
#: SIZE_NEIGHBOURS - 1 neighbours.  Measured on uniformly random sphere
#: samples (the hard case for holes): the largest ratio was 1.70-1.92 at 4k
#: points and 1.99-2.41 at 50k (3 seeds each), 1.45 on kitten.xyz; 3.0 never
#: shrinks such a splat, while stray points (the largest splat was 397x the
#: median on poste_france.xyz, 45x / 89x on kitten / hippo1 with 1 % injected
#: outliers) end at most 3x their neighbours
SIZE_CAP_REL_NEIGHBOURS = 3.0
#: a point is on a boundary (open border, scan edge) when its neighbours,
#: projected into its tangent plane, leave an angular gap wider than this
#: (degrees).  On a cut random hemisphere 97 % of the points within half a
#: spacing of the cut and 86 % within one spacing exceed it; on a closed random
#: sphere 0.5 % do (the wide empty circles of random samples), which is why the
#: boundary rule below only caps and never opens a hole: 0 uncovered of 300k
#: surface probes on 4 closed spheres of 4k and one of 50k points
BOUNDARY_GAP_DEG = 150.0
#: a boundary splat (BOUNDARY_GAP_DEG for point clouds; for meshes a vertex
#: of a face that touches a border edge, i.e. the border and the ring inside
#: it) is at most this times the median radius of its neighbours, so it does
#: not overhang the border as a flap.  Cut random hemisphere (20k sphere
#: points): border radius / median of its interior neighbours at most 1.66
#: (median 1.20), against 2.34 (1.25) uncapped.  Planar grid (spacing h) whose
#: border is a strip of 8h-long sliver triangles: overhang beyond the border
#: 5.54 h before, 2.69 h capping only the border vertices, 1.18 h with the
#: ring.  bunny00.off cut in half: 0 of 299,464 triangle samples uncovered;
#: 1.0 instead of 1.2 left 10 uncovered next to the cut
BOUNDARY_CAP_REL_NEIGHBOURS = 1.2
#: statistical outliers (PCL StatisticalOutlierRemoval / Open3D
#: remove_statistical_outlier): the mean distance to the OUTLIER_NEIGHBOURS
#: nearest other points, compared in log space with the global mean +
#: OUTLIER_STD_RATIO standard deviations.  Log space makes the test scale-free
#: (a region sampled 2x sparser is a constant shift, not a tail).  Measured
#: on clean files (points flagged): linear space k=8, ratio 4: kitten 0, hippo1
#: 30, bunny00 63; log space: 0, 9, 2.  With 1 % uniform outliers in the
#: bounding box plus 5 far strays, recall of the injected points more than 5
#: spacings off the surface is 0.83-1.00 (kitten and poste_france 1.00,
#: hippo1 0.87, bunny00 0.83) at a precision of 0.98-1.00 (poste_france's
#: own strays not counted as false); k = 16 or 24 flagged more clean points
#: (16-22 on hippo1) for no better recall
OUTLIER_NEIGHBOURS = 8
OUTLIER_STD_RATIO = 4.0
#: a point with no other point within this many median nearest-neighbour
#: distances is isolated (an outlier whatever the statistics say).  Largest
#: clean value: 6.4 on hippo1.ply, 7.7 on bunny00.off (mesh vertices next to
#: long edges); poste_france.xyz has stray points at 11-1052
ISOLATED_SPACINGS = 10.0
#: an outlier's splat (OUTLIER_* / ISOLATED_SPACINGS) that is kept is at most
#: this times the median radius of its neighbours that are not outliers (of
#: all such splats when every neighbour is an outlier): a stray is drawn no
#: larger than the surface splats next to it instead of up to 21x the median
#: (poste_france.xyz as read); clusters of strays escape the neighbour cap
#: above because their neighbours are strays too
OUTLIER_RADIUS_REL_MEDIAN = 1.0
#: stray clusters: pieces of the neighbour graph (cut at the isolation radius)
#: holding at most this fraction of the points.  poste_france.xyz after the
#: statistical and isolated tests keeps 7 far clusters of 8-28 points (0.09-
#: 0.31 % of 9,031) that set its bounding box (diagonal 258 for a 30-unit
#: object); 0.5 % catches them while kitten, hippo1 and bunny00 (one piece
#: each) lose nothing
STRAY_CLUSTER_MAX_REL = 0.005
#: rounds of splatedit.model.sizing.settle_radii (the neighbour cap applied
#: again to the neighbours of splats the caps shrank, so that the cap holds
#: against the sizes as drawn).  Rotating-sensor scans of
#: data_tools/make_radar_scan.py (lidar and radar, seeds 0-1, 1-2 sweeps,
#: 4k-90k points): the largest splat was 2.2-13.6x the median of its 15
#: nearest neighbours' radii (multipath ghosts and near-sensor dust of which
#: only some points are flagged as outliers; poste_france.xyz 6.1x), 3.0x
#: after settling; it took 1-2 rounds and shrank 0-0.1 % of the splats
#: (poste_france 0.7 %, kitten and hippo1 none); 12 more scans (seeds 2-5,
#: radar 1 and 3 sweeps, lidar 1 sweep): 3.0x after 1-3 rounds
SIZE_SETTLE_ROUNDS = 8


# ---------------------------------------------------------------------------
# Scan scale: estimation speed, levels of detail, rendering at 10M (issue 11, parts 4-6)
# ---------------------------------------------------------------------------
#: closed-form 3x3 eigenvectors (splatedit.model.pca): a row falls back to
#: np.linalg.eigh when the largest cross product of two rows of A - lambda I
#: is below this fraction of p^2 (p^2 ~ the squared eigenvalue spread; the
#: cross product ~ (l1 - l3)(l2 - l3)), i.e. when l2 - l3 < ~3e-4 p and the
#: closed form's smallest eigenvalue (error ~ sqrt(eps) p there) could tilt
#: the vector by more than ~1e-5 rad.  Measured on the bunny sampled with 1M
#: points: 0 of 1M rows fall back and the largest angle to eigh's vector is
#: (see tests/model/test_pca.py) below 1e-6 rad
EIGEN_CROSS_MIN_REL = 1e-3
#: orientation (splatedit.model.estimate.orient_normals): k-NN edges whose two
#: normals are within this angle are "safe" and oriented along any spanning
#: forest of them (BFS, O(n)); Hoppe's MST then runs only over the pieces
#: they form.  Kruskal over every k-NN edge took 2.0 of the 3.1 s of
#: orientation at 1M points; with 10 degrees 95% of the bunny's k-NN edges
#: are safe and the MST shrinks to (see the measurement in docs/PERFORMANCE.md)
ORIENT_SAFE_ANGLE_DEG = 10.0
#: Renderer.set_cloud uploads geometry and colours through one staging
#: buffer of this many splats (36 MB of float32 geometry).  The whole-cloud
#: float32 array + whole-cloud staging buffer it replaces cost 720 MB at 10M
#: splats; chunks of 1M keep the per-submit overhead (one fence wait, ~1 ms)
#: negligible next to the 36 MB copy
RENDER_UPLOAD_CHUNK_SPLATS = 1 << 20
#: LodPyramid(background=True): the preview level is clustered from an evenly
#: strided sample of this many splats.  A 1M-splat pyramid takes 0.6-1.3 s
#: here (load 5-7), 10M 7-9 s; the preview of a 10M cloud is one 1M-sample
#: level, so the editor's first image comes after ~1 s instead of ~9 s
LOD_PREVIEW_SAMPLE_SPLATS = 1_000_000
#: orientation: only the safe edges to this many nearest neighbours form the
#: BFS forest (the others join the MST phase, where most fall inside one
#: piece and are dropped); halves the graph that connected_components and
#: the BFS copy and transpose (measured below in docs/PERFORMANCE.md)
ORIENT_FOREST_NEIGHBOURS = 4


# ---------------------------------------------------------------------------
# Tiled estimation of large raw clouds (issue 11 part 4)
# ---------------------------------------------------------------------------
#: points per k-d tree tile of splatedit.model.tiles.tiled_knn (its cells and
#: their halo are queried against one small tree).  1M bunny points, k = 16,
#: CPU seconds / tree points per point (halo overhead), load 6.5: 2^14 2.61 /
#: 1.34, 2^16 2.74 / 1.18, 2^18 2.98 / 1.07 (one global tree: 2.59 s); 2^16
#: keeps a tile's tree (~80k points) cache-sized with a small halo
TILE_POINTS = 65536
#: mean points per occupied octree cell of the tiles (the halo is one cell
#: wide, so a cell must be wider than most k-th neighbour distances).  Same
#: cloud: 64 -> level 7, 1.18 tree points per point, 0 retried queries; 16 ->
#: level 8, 2.10 and 25,654 retried (cells narrower than the 16-NN radius)
TILE_CELL_POINTS = 64
#: a tiled k-th distance counts as exact only below (1 - this) times its bound
#: (the bound comes from float64 grid coordinates, exact to ~1e-16 relative)
TILE_EXACT_MARGIN_REL = 1e-9
#: points per chunk of the orientation's forest pass (splatedit.model.orient;
#: a piece of the safe-edge forest ends at a chunk border).  1M bunny points,
#: CPU seconds / pieces / piece-graph edges: 2^16 0.90 / 783 / 1475, 2^17 0.97
#: / 609, 2^18 0.97 / 472, 2^19 1.14 / 373, one chunk 1.26 / 264 (all 100%
#: outward): the MST over a few thousand pieces costs nothing and a chunk's
#: temporaries (~200 bytes a point) stay ~13 MB
ORIENT_CHUNK_POINTS = 1 << 16
#: tests/model/test_tiles.py: traced numpy peak of estimate_splats on 1M raw
#: bunny points, above the input, per point.  Measured (tracemalloc, same
#: session): 245 bytes on this branch (156 of them the sorted points, k-NN
#: table and distances, normals and order; 48 the output u and v; ~70 a
#: fixed ~70 MB of per-chunk temporaries, so the figure falls with n)
#: against 494 before the tiled estimation
ESTIMATE_PEAK_EXTRA_BYTES_PER_POINT = 300
#: coarser octree levels tiled_knn retries inexact answers on before it
#: queries the rest against one tree over all points.  1M bunny points + 1%
#: uniform noise + 50 far strays, CPU s / tree points per point / left to the
#: global tree (one global tree alone: 3.3 s): 0 levels 3.33 / 1.56 / 8,664;
#: 1: 3.60 / 2.90 / 7,340; 2: 4.30 / 5.4 / 119; retrying all the way to the
#: root: 5.79 / 13.6 (coarse 3x3x3 blocks around strays hold most of the
#: surface).  One level resolves the points near a cell wall without a tree
#: over the whole cloud (poste_france.xyz: 105 retried, 39 left)
TILE_RETRY_LEVELS = 1


# --- Orientation: the top of a component votes (a stray above a scan) ------------
# 100k points on a unit sphere with 1% radial noise plus 50 strays 1.5-4.5 radii
# above: with the single highest point as the seed, seed 0 of the test cloud came
# out 0.03% outward (the highest point was a stray); with the vote 100%.
#: points of the deterministic sample the vote is taken on (every n // this-th point)
ORIENT_VOTE_SAMPLE = 200_000
#: a component with fewer sampled points keeps its seed's orientation
ORIENT_VOTE_MIN_VOTERS = 64
#: share of a component's sampled points (its highest) that vote
ORIENT_VOTE_TOP_FRACTION = 0.01
#: the voters' mean oriented n_z must be below minus this to turn a component
#: (the tops of the closed test scans give +0.6..+0.9; a vertical wall about 0)
ORIENT_VOTE_MIN_MEAN_NZ = 0.2


# ---------------------------------------------------------------------------
# Framing the main body, not the outliers (splatedit.model.extent; issues 10/11)
# ---------------------------------------------------------------------------
#: the main body's shell is FRAMING_BODY_SHELL x this quantile of the points'
#: distances to their median.  Not the 99th: poste_france.xyz has 1.4 % of
#: its points in far clumps, so its 99th percentile (102 units) lies among
#: them; its 90th is 7.9 units (body up to 12.7 units, clumps from 100)
FRAMING_BODY_QUANTILE = 0.90
#: ... times this.  The farthest point of a clean model lies within 1.20 x
#: (kitten), 1.23 x (hippo1), 1.29 x (bunny, bunny00) the 90th percentile
#: (a uniform segment: 1.11 x, a ball 1.04 x), their boxes' farthest corners
#: within 1.67 x: all inside, framed as before.  poste's body reaches 1.6 x,
#: its clumps start at 12.7 x
FRAMING_BODY_SHELL = 2.0
#: the main body is framed instead of the full box only when its box's
#: diagonal is under this fraction of the full box's ("much smaller": the
#: full box would show it at less than half the size); poste: 0.08
FRAMING_OUTLIER_RATIO = 0.5
#: ... and when at most this fraction of the points lies outside the shell
#: (poste: 1.4 %); more is a sparse part of the model, not a few outliers
FRAMING_OUTLIER_MAX_FRACTION = 0.05
#: the median and the quantile are taken on a seeded subsample of at most
#: this many points (the box and the far count are exact, one pass over all).
#: The 90th-percentile distance of the bunny from 20k of its 37.7k points is
#: within 0.5 % of the exact one (a quantile's standard error ~ sqrt(q(1-q)/m))
FRAMING_SAMPLE_POINTS = 20_000
#: the front view's reference direction (splatedit.model.orientation.
#: front_direction) is +Z unless the up vector is within ~25 degrees of
#: +-Z (|up_z| >= this), then -Y: the editor's turntable used it first; any
#: value well away from 0 and 1 keeps the reference far from parallel to up
FRONT_VIEW_Z_UP_COS = 0.9

# ---- batch conversion of tiles (splatedit.io.batch)
#: a tile's normals and sizes are estimated over its own points and its
#: neighbour tiles' points within this many *neighbourhood radii* of its box
#: (the tile's median distance to its SIZE_NEIGHBOURS-th neighbour, about 2.3
#: point spacings on a surface): a splat's size depends on its neighbours'
#: sizes (the median cap of model/sizing.py), two neighbourhoods deep.
#: Measured on 3 x 2 terrain tiles of 20k points (splatedit.bench.batch),
#: points within 2 radii of an inner border against the merged cloud
#: estimated at once: halo 0 (a plain per-file loop): normals up to 85 deg
#: and radii up to 133 % off; 1: 43 deg, 12 %; 2: axes equal (2e-6 deg,
#: rounding) and radii exact, but 0.95 % of the normals oriented the other
#: way; 3 and 4: axes and radii equal, no normal flipped.  At 10 tiles of
#: 200k the axes stay equal; a few orientation pieces and outlier caps still
#: differ (global steps, see docs/PERFORMANCE.md)
TILE_HALO_NEIGHBOURHOODS = 3.0
#: the neighbourhood radius is the median over a seeded sample of this many
#: of the tile's points (exact enough: a median's relative standard error is
#: ~1/sqrt(m), 2.2 % at 2000)
TILE_SPACING_SAMPLE = 2000

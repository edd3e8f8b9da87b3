"""Tolerances and tuning constants of selections, their closure and the neighbour graph (splatedit.select).

Part of :mod:`splatedit.tolerances` (import them from there); every value
carries the measurement behind it.
"""


# --- selection closure (splatedit.select) ---------------------------------
#: neighbour graph: k nearest neighbours per splat (symmetrised).  10 keeps a
#: surface sampled by a scan or a mesh connected (every splat has neighbours
#: all around) without linking the two sides of thin parts much more often
#: than their sampling does anyway
GRAPH_NEIGHBOURS = 10
#: an edge is cut when it is longer than this times the smaller local scale of
#: its two splats (median distance to their k neighbours): outliers and
#: bridges across gaps between parts do not connect
GRAPH_EDGE_MAX_REL = 3.0
#: the graph's coarse subsample (every this many-th splat) answers k-d queries
#: far from the surface (closure's rays deep inside a thick part): 500 queries
#: 0.05 inside a 1M-splat bunny took 51 ms in the full tree
GRAPH_COARSE_STRIDE = 16
#: closure rule 1 for a handle: its thickness bound T is this times the
#: handle's RMS radius (the support bounds it).  A handle painted from one
#: view over a head's face: the front hemisphere of a sphere of radius R has
#: RMS radius sqrt(3/4) R = 0.87 R and the back lies 2 R behind its pole
#: (2.3 RMS radii); 3.0 leaves a margin for a face painted short of the
#: silhouette.  A 1.0 bound (the support's) left the back of the head out of
#: the handle: turning the head smeared it (22x in the tester's session)
CLOSURE_HANDLE_THIN_MAX_REL = 3.0
#: an edit script's index list counts as a one-view stroke (its hidden back
#: side may join, splatedit.script.run.close_edit) when at least this share of
#: its splats face the side of its mean normal: a stroke on the bunny's ear
#: from one view (the team's one_view_edit.py): 99.2%; a ball of radius 0.25
#: around the ear tip, both sides of the ear and part of the head: 66%
CLOSURE_ONE_SIDED_SHARE = 0.95
#: closure rule 1: normals of a thin part's two sides face opposite ways
#: within acos(-0.5) = 120 degrees
CLOSURE_OPPOSITE_COS = 0.0
#: closure rule 1: the thickness bound T of a thin part, times the RMS radius
#: of the painted selection
CLOSURE_THIN_MAX_REL = 1.0
#: closure rule 1 casts a ray into the material from every painted splat:
#: samples at depths CLOSURE_RAY_START spacings * CLOSURE_RAY_STEP^j (up to
#: T), each looking for the nearest splat within CLOSURE_RAY_RADIUS_REL times
#: its depth (at least one spacing).  With step 1.5 and radius 0.35 the
#: searched depth intervals [0.65, 1.35] d overlap, so no thickness is
#: skipped; 1.5 spacings keeps the first sample off the painted surface
CLOSURE_RAY_START = 1.5
CLOSURE_RAY_STEP = 1.5
CLOSURE_RAY_RADIUS_REL = 0.35
#: splats tested where a ray meets the first surface (one per ray left about
#: a third of the bunny ear's back unreached: rays bunch up behind curved fronts)
CLOSURE_RAY_HITS = 4
#: at most this many rays per closure (an even subsample of the painted
#: splats): the hits only seed the growth over the graph, which reaches the
#: rest of the back side
CLOSURE_RAY_MAX = 500
#: ray samples deeper than this many spacings query the graph's coarse subsample
CLOSURE_RAY_COARSE_DEPTH = 8.0
#: k-d tree queries of closure run on all cores only for batches at least this
#: large (starting the threads took about 2 ms per call, more than a few
#: thousand queries gain)
CLOSURE_PARALLEL_QUERIES = 20000
#: closure rule 1, growing the rays' hits over the graph: a neighbour of a back
#: splat is tested against that splat's front and the painted splats within
#: this many rings of it (the straightest one becomes its own front, so the
#: match follows a tapering part ring by ring).  One-view ear strokes on the
#: bunny: the same figures with 1 and 2 rings (0 tears, at most 5 splats
#: beyond 4x in one view); 1M-splat ear stroke 80 ms with 1, 96 ms with 2
CLOSURE_FRONT_RINGS = 1
#: the selection's RMS radius (the thickness bound T) is taken from an even
#: subsample of at most this many splats (it bounds, it does not measure)
CLOSURE_RMS_SAMPLES = 4096
#: closure rule 1: the painted splat lies within acos(this) of straight
#: behind the candidate along both normals (a part's two sides face each
#: other through its thickness; other surfaces within T lie off to the side)
CLOSURE_BACK_CONE_COS = 0.7
#: closure rule 2: morphological closing radius in rings (fills slits and
#: rims up to twice this wide)
CLOSURE_GAP_RINGS = 2
#: closure rule 3: unselected components within this many rings of the
#: selection that reach no farther are enclosed islands
CLOSURE_ISLAND_RINGS = 8
#: a stroke's closure (``changed``) works on the splats within this many point
#: spacings of the box of the changed splats: the graph rules reach
#: CLOSURE_ISLAND_RINGS + 2 CLOSURE_GAP_RINGS rings, and a ring of the
#: 10-neighbour graph spans up to about 2 spacings
CLOSURE_REGION_RINGS = 2 * (CLOSURE_ISLAND_RINGS + 2 * CLOSURE_GAP_RINGS) + 2
#: closure rule 4: unselected splats closer to a handle than max(band width,
#: this times the handle's RMS radius, about its diameter) join the support,
#: so the deformation has room to fall off: a fixed splat next to a moving
#: handle tears.  One-view strokes on the bunny's ears (4 views, translation
#: by 8% of the diagonal): 1.0 left up to 23 splats stretched > 4x (max 4.6x),
#: 1.5 up to 3 (6.5x), 2.0 none (max 3.4x)
CLOSURE_HANDLE_MARGIN_REL = 2.0
#: ... but at most this fraction of the model's bounding-box diagonal: a big
#: handle (the bunny's head, RMS radius 0.2 of a 1.7 diagonal) would otherwise
#: pull half the body into the support although the painted support already
#: gives it room; ear-tip handles (2 x RMS radius up to 0.12) are not capped
CLOSURE_HANDLE_MARGIN_MAX_REL = 0.08


# --- selection graph at scan scale (splatedit.select.graph, issue 11 part 5) ---
#: rows per chunk of NeighbourGraph.build's passes over its k-NN table
#: (local scales, edge rule, renumbering): a chunk's float64 temporaries are
#: about 50 bytes per row and neighbour (~65 MB per 2^17 rows at k = 10),
#: small next to the (n, k + 1) float32 + int32 tables (1M splats: 88 MB)
GRAPH_BUILD_CHUNK = 1 << 17
#: NeighbourGraph.build decides "edge length <= GRAPH_EDGE_MAX_REL x the
#: smaller local scale" on tiled_knn's float32 distances (each within 2^-24
#: = 6e-8 relative of the float64 one, the median scales likewise); a
#: comparison closer than this (relative) is redone in float64, so the edges
#: are exactly those of the float64 rule (16x the worst float32 error)
GRAPH_EXACT_MARGIN_REL = 1e-6
#: rows per block when the graph gathers neighbour lists of many splats
#: (subgraph, boundary, closure's islands): the int64 position temporaries
#: are 16 bytes per edge end of the block, so a block of 2^16 rows (~11 ends
#: each) costs ~12 MB instead of 16 bytes per end of the whole request
#: (1.4M-splat shell at 5M: ~250 MB)
GRAPH_ROWS_CHUNK = 1 << 16

# --- mirror (X-symmetry) selection (splatedit.select.mirror) ---------------
#: a splat's mirror image is the splat nearest to its reflection when that
#: one is at most this many median neighbour spacings away (and a splat whose
#: reflection lands nearest to a selected one joins too).  Measured, a strip
#: of one side mirrored (the fraction of the other side's strip found; no
#: splat away from the strip's edge was ever taken):
#:   jittered 60x60 grid (0.25 steps, tests/select/test_mirror.py):
#:     0.5: 42 %, 1.0: 94 %, 1.5 - 3.0: 100 %
#:   Poisson-sampled sphere, 100k (the worst case: random gaps):
#:     1.0: 50 %, 1.5: 79 %, 2.0: 92 %, 2.5: 96 %, 3.0: 97 %
#: 2.0 takes nearly all of a scan's sampling (between the two) while staying
#: within two spacings of the reflected surface; the closure that follows
#: fills the few holes left.
MIRROR_MATCH_SPACINGS = 2.0

"""Tolerances and tuning constants of the interactive editor: tools, GUI panels, frame scheduling, commits (splatedit.app).

Part of :mod:`splatedit.tolerances` (import them from there); every value
carries the measurement behind it.
"""


# --- interactive editor (splatedit.app) ----------------------------------
#: orbit camera: pitch is kept within +-this many degrees of the horizon
EDITOR_PITCH_LIMIT_DEG = 89.0
#: orbit camera: radians of orbit per pixel of mouse motion
EDITOR_ORBIT_RAD_PER_PX = 0.008
#: orbit camera: distance factor per wheel step (zoom in for positive steps)
EDITOR_DOLLY_STEP = 0.85
#: orbit camera: closest and farthest distance, relative to the model radius
EDITOR_MIN_DIST_REL = 1e-3
EDITOR_MAX_DIST_REL = 1e3
#: orbit camera clip planes: distance -+ this many model radii
EDITOR_CLIP_RADII = 2.0
#: orbit camera: the near plane is at least distance * this, and at least
#: EDITOR_NEAR_MIN (model units); far is at least near * EDITOR_FAR_MIN_NEAR
EDITOR_NEAR_MIN_REL = 1e-3
EDITOR_NEAR_MIN = 1e-6
EDITOR_FAR_MIN_NEAR = 10.0
#: orbit camera: a framed sphere fills the view up to this margin
EDITOR_FRAME_MARGIN = 1.1
#: a left press this close to a curve dot (pixels) drags it
EDITOR_CURVE_DOT_PICK_PX = 10
#: length of the translate gizmo's arrows (pixels); arrows shorter on screen
#: than EDITOR_GIZMO_MIN_PX (seen end-on) are hidden; a press within
#: EDITOR_GIZMO_HIT_PX of an arrow's outer three quarters grabs it
EDITOR_GIZMO_PX = 70
EDITOR_GIZMO_MIN_PX = 12
EDITOR_GIZMO_HIT_PX = 7.0
#: rotate rings of the gizmo: a circle of this radius (pixels at the handle's
#: depth) around the handle centroid per world axis, drawn with this many
#: segments; a ring whose axis makes |axis . view direction| below
#: EDITOR_GIZMO_RING_MIN_COS is seen almost edge-on and hidden.  The uniform
#: scale grip is a screen circle of radius EDITOR_GIZMO_SCALE_PX (outside the
#: arrows); both are grabbed within EDITOR_GIZMO_HIT_PX
EDITOR_GIZMO_RING_PX = 52
EDITOR_GIZMO_RING_SEGMENTS = 64
EDITOR_GIZMO_RING_MIN_COS = 0.2
EDITOR_GIZMO_SCALE_PX = 92
#: depth tolerance of the brush's visibility test, in pixel footprints
EDITOR_PICK_TOL_PX = 6.0
#: the brush radius range (pixels)
EDITOR_BRUSH_MIN_PX, EDITOR_BRUSH_MAX_PX = 2, 400
#: brush radius factor per wheel step (Ctrl+wheel) and per [ / ] key press
EDITOR_BRUSH_WHEEL_STEP = 1.15
EDITOR_BRUSH_KEY_STEP = 1.2
#: seconds without motion after which the full-quality frame is drawn
EDITOR_REFINE_DELAY_S = 0.2
#: full-quality frames predicted slower than this (ms) are refined progressively after
#: motion stops (app/view/progressive_refine.py; SPLATEDIT_REFINE_ABOVE_MS overrides it)
EDITOR_ASYNC_REFINE_MS = 400.0
#: assumed full-quality cost (ms per splat at the window size) before the first measurement
EDITOR_GUESS_MS_PER_SPLAT = 6e-4
#: models with more splats than this get a level-of-detail pyramid
EDITOR_LOD_MIN_SPLATS = 60_000
#: the moving frame's budget (ms): 30 frames/s (issue 19 item 9), or the editor's
#: ``budget_ms`` when that is smaller.  The whole frame is budgeted (GUI and present
#: are measured and subtracted, FrameScheduler.frame_overhead_ms); still frames and
#: the progressive refinement keep ``budget_ms`` (100 ms) as their frame interval
EDITOR_MOVING_BUDGET_MS = 1000.0 / 30.0
#: splat budgets of the editor's level-of-detail pyramid (levels above half the
#: cloud are skipped).  The 12k level is for 30 frames/s on lavapipe under load:
#: at 1280x720 / 3 on 2 loaded cores a 38k-splat level took 25-40 ms to render
#: and presenting (blit + GUI + swapchain) another 15-25 ms (docs/PERFORMANCE.md,
#: "Editor frame rate"); 60k: a 100k model moves as a level instead of all its splats
EDITOR_LOD_BUDGETS = (400_000, 120_000, 40_000, 12_000)
#: level-of-detail grid cell = this * sqrt(surface area / splat budget)
#: (a square grid of cell c gives about area / c^2 clusters; the margin
#: absorbs the clusters cut by cell borders)
EDITOR_LOD_CELL_FACTOR = 1.08
#: smallest level-of-detail grid cell, relative to the bounding-box diagonal
EDITOR_LOD_MIN_CELL_REL = 1e-6
#: an axis-constrained grab does nothing while the axis's screen direction
#: (|(a . right, a . up)|, 1 when the axis lies in the view plane) is shorter
#: than this (the axis points at the viewer)
EDITOR_AXIS_MIN_SCREEN_LEN = 1e-6
#: a mouse-driven scale factor is clamped to at least this; a typed factor
#: must be > 0 (a negative one would mirror the handle and turn its normals
#: inside out)
EDITOR_MIN_SCALE_FACTOR = 1e-3


# ---------------------------------------------------------------------------
# Editor: 3D brush, selection tools and closure (issue 8, editor side)
# ---------------------------------------------------------------------------
#: the splats closure added to the selection are highlighted this long (s):
#: long enough to be seen after releasing the mouse (a reaction takes ~0.3 s),
#: short enough not to hide the support colour while the next stroke starts
EDITOR_CLOSURE_HIGHLIGHT_S = 1.2
#: fitted bases kept after they are replaced (a commit, a selection change), so
#: that undo / redo back to their document takes them again at once instead of
#: refitting (the curve's dots and the pending pose are drawn on the surface at
#: once, not floating over it until the fit ends).  Kept without their CPU
#: apply cache (rebuilt by the next commit); sizes measured with
#: fitting.basis_bytes, one handle: the bunny's ear (3,017 support splats)
#: 1.0 MB, 99,000 support splats of a 300k bunny 15.5 MB (fitted in 6 s on
#: the loaded 2-core machine, which undo now skips); so the last 4 bases, at
#: most 256 MB in all (a larger one is not kept: it is refitted)
EDITOR_FIT_KEEP_BASES = 4
EDITOR_FIT_KEEP_BYTES = 256 << 20
#: clouds up to this many splats get their neighbour graph built on the spot
#: when a tool needs it before the background job has finished (measured
#: NeighbourGraph.build on 2 shared cores: bunny 37.7k 0.28 s, 200k random
#: points 2.3 s; 100k keeps the wait near one second)
EDITOR_GRAPH_SYNC_MAX_SPLATS = 100_000


# ---------------------------------------------------------------------------
# Editor architecture: up axis, help paging, display options (issue 10)
# ---------------------------------------------------------------------------
#: a normal counts as aligned with a world axis when |n . axis| >= this
#: (25.8 degrees).  Floors and flat undersides of scans fall well inside it
UP_AXIS_ALIGNED_COS = 0.9
#: ground signal: at least this fraction of all normals facing one signed axis.
#: Measured: the bunny (Y-up, no floor) 9-16% on every axis, the kitten 10-12%;
#: hippo1.ply, a one-sided scan taken from +Z (Y-up: its legs point to -Y), has
#: 37% facing +Z, which is why the band test below is needed
UP_AXIS_GROUND_MIN_FRACTION = 0.25
#: ... and at least UP_AXIS_FLOOR_MIN_IN_BAND of those points lie within this
#: fraction of the model's extent from its bottom along that axis (a floor, a
#: flat underside).  hippo1's +Z-facing points: 3% within the bottom tenth of
#: z (they cover its whole depth); a floor: all of them
UP_AXIS_FLOOR_BAND = 0.1
#: with no word from the file and no floor, a model at least this many times
#: taller along Z than along X and Y stands Z-up (a figure from a Z-up tool:
#: a standing person is 3.5-6x taller than wide or deep with the arms down);
#: 3x keeps Y-up models that are long along Z lying as authored (a car about
#: 2.5x as long as wide, the bunny 1.0x)
UP_AXIS_TALL_Z_RATIO = 3.0
UP_AXIS_FLOOR_MIN_IN_BAND = 0.5
#: the floor rule runs on every n // this-th splat of a large model: its two tests
#: are shares of points (binomial error of a share near the 0.25 / 0.5 limits with
#: 200k samples: 0.1%); 10M splats: 0.07 s instead of 3.5 s (normals 2.8 s + rule 0.7 s)
UP_AXIS_SAMPLE = 200_000
#: splat size scale steps (Shift+[ / Shift+]) and its range: 0.25x makes a
#: dense scan's splats visibly separate points, 4x closes the holes of a
#: sparse one (poste_france at 1x shows gaps of ~2 splat radii)
EDITOR_SPLAT_SCALE_STEP = 1.25
EDITOR_SPLAT_SCALE_MIN = 0.25
EDITOR_SPLAT_SCALE_MAX = 4.0
#: the help window keeps this many pixels free at the window's edges, and one
#: PageDown moves by its visible lines minus this overlap (context kept)
EDITOR_HELP_MARGIN_PX = 12
EDITOR_HELP_PAGE_OVERLAP = 2
#: grey albedo (sRGB) of the uniform-grey shading mode (M): 0.72 (0.485
#: linear) keeps a lit pixel under 1.0 with RENDER_LIGHT (0.485 * (0.2 + 0.8)
#: + 0.25 = 0.735), so highlights do not clip, and a grazing one (ambient
#: only, 0.1 linear) still reads against the white background
RENDER_GREY_ALBEDO = 0.72
#: eye-dome lighting (`render --edl`, shaders_glsl/resolve_edl.frag): shade =
#: exp(-300 * strength * mean over 8 neighbours at this radius of the log2
#: depth step).  Strength 1 and radius 1.4 px are the defaults of Potree's EDL
#: (its 8 neighbours at 1.4 px round to the adjacent pixels).  Measured on the
#: grey step scene of tests/render/test_edl.py (depth 3.0 | 3.1, log2 step
#: 0.047, 96x64, raster and compute alike): the far side's edge column goes
#: from 221 to 24 (sRGB; 0.11x), every other column stays within 1/255
RENDER_EDL_STRENGTH = 1.0
RENDER_EDL_RADIUS_PX = 1.4


# ---------------------------------------------------------------------------
# Gaussian splatting scenes in the editor (issue 13: editing, rigid reference)
# ---------------------------------------------------------------------------
#: a rigid motion applied as a deformation (support = every Gaussian, handle
#: 80 % of them, 90 degrees about (0, 0.6, 0.8) plus a shift) vs the scene
#: transformed rigidly with SH rotation, both drawn by the Vulkan renderer at
#: 160x120 (tests/render/test_gaussians.py): mean |difference| over RGB on the
#: scene pixels (8-bit steps) and the worst pixel.  Measured on
#: bunny_gaussians.ply from 3 views: CPU-deformed scene 0.0 (identical images),
#: GPU deformation (linear and rotation-aware) 0.004-0.009, worst 1 step
#: (float32 basis rows, polar rotation by Newton iterations)
GS_RIGID_IMAGE_MEAN_TOL = 0.1
GS_RIGID_IMAGE_MAX_TOL = 3
#: the same rigid reference drawn with the SH left unrotated (the colour bleed
#: of graphdeco-inria/gaussian-splatting issue 176) must differ by at least
#: this mean (8-bit steps on the scene pixels): measured 15.9-25.2
GS_BLEED_MIN_MEAN = 5.0


# --------------------------------------------------------------------------
# Editor GUI (Dear ImGui panels and GPU overlays, issue 10 parts 1-2, 5)
# --------------------------------------------------------------------------
#: the last closure's highlight is drawn as small squares in ImGui's draw list,
#: one per distinct pixel; above this many they are thinned evenly.  Measured
#: (2 loaded cores): 0.73 us of Python per square for the draw-list calls, so
#: 20,000 squares add ~14 ms to a frame that shows a highlight (it flashes for
#: about a second after a grow / shrink / connected step); all 37,706 splat
#: centres of the bundled bunny framed in a 960x600 view fall on 26,496
#: distinct pixels, so even a whole-model highlight is barely thinned
EDITOR_GUI_MAX_HIGHLIGHT_DOTS = 20_000
#: width of the side panel (pixels, ImGui's default 13 px font): its widest
#: row, the three "move" fields with their label, measures 252 px, plus the
#: window padding and the scroll bar; a 960 px window keeps 640 px of view
EDITOR_GUI_PANEL_WIDTH = 310
#: width of the panel's sliders (brush radius, splat size; pixels): their value
#: and label are written beside them ("300 px  brush radius" measures 140 px in
#: the default font), 120 + 8 spacing + 140 fits the panel's 282 px content
EDITOR_GUI_SLIDER_WIDTH = 120
#: the help window goes beside the panel when that space is at least this wide
#: (px), else over the whole window (the panel steps aside until it closes);
#: the longest help line measures 763 px in the default font, narrower help
#: windows scroll horizontally; 420 px shows every key column and most text
EDITOR_GUI_HELP_MIN_WIDTH = 420
#: a numeric rotation whose axis is shorter than this is refused (the axis is
#: a direction, normalised before use; a zero one has no direction)
EDITOR_GUI_MIN_AXIS_NORM = 1e-9
#: frames the editor draws after an input event without waiting for the next
#: one: ImGui trickles a click's press and release over two frames and shows
#: the result (a highlighted button, a focused field) in the third; 4 leaves
#: one to spare.  Without it the idle loop's 0.5 s wait delayed a click's
#: effect by up to 0.5 s
EDITOR_GUI_SETTLE_FRAMES = 4


# ---------------------------------------------------------------------------
# Progressive refinement in the editor (issue 11 part 5)
# ---------------------------------------------------------------------------
#: smallest chunk of splats per progressive step: 1M splats at 1280x720 on lavapipe
#: (2 loaded cores) took 39 ms per visibility step and 66 ms per colour step (resolve +
#: readback included) at 20k, 5.5 s in all vs 3.2 s in one submit; smaller chunks
#: add more per-submit overhead than they save in frame time
EDITOR_PROGRESSIVE_MIN_CHUNK = 20_000
#: a step's chunk grows at most this factor at a time (the first steps' times
#: include pipeline creation and are not representative of the cost per splat)
EDITOR_PROGRESSIVE_CHUNK_MAX_GROWTH = 2.0


# ---------------------------------------------------------------------------
# Framing beside the side panel (Home / F into the free part of the window)
# ---------------------------------------------------------------------------
#: Home / F frame into the window minus the side panel's column when what is
#: left is at least this fraction of the window's width (height: below the
#: menu bar); narrower, the whole window.  At the default 1280x720 the panel
#: (EDITOR_GUI_PANEL_WIDTH + margin) leaves ~0.75 of the width; at 640 px
#: ~0.5; a quarter still shows a framed model about 160 px wide at 640 px
EDITOR_FRAME_MIN_FREE_FRACTION = 0.25


# ---------------------------------------------------------------------------
# Commits in the editor's background (issue 10 "habits": long work shows progress)
# ---------------------------------------------------------------------------
#: a commit whose estimated time (below) is under this runs on the UI thread
#: (no progress bar flashing for a frame; the window misses at most ~3 frames
#: at 60 Hz).  Commits measured with a third of the model as support (2 cores
#: shared by 8 engineers, load 4.5-7): the bundled bunny (12.6k) 26-51 ms; 1M
#: splats (333k) 2.0-2.4 s; a 100k-Gaussian scene (33k) 0.87-1.0 s
EDITOR_COMMIT_SYNC_MS = 50.0
#: estimated commit cost per support splat (the chunked basis apply; each
#: commit's basis is fresh, so its first call also builds the hot-path
#: arrays).  Measured (loaded machine): the bundled bunny (mesh order: long
#: runs of support rows) 12.6k support 26 ms in all, ~2 us per splat; 1M
#: splats in random order (short runs, gathered) 333k support 2.0 s cold /
#: 0.92 s warm, 6 / 2.8 us.  3 us: the bunny's edits stay synchronous, a
#: scattered cloud near the threshold may block ~2x the 50 ms, once
EDITOR_COMMIT_US_PER_SUPPORT_SPLAT = 3.0
#: estimated commit cost per splat of the whole cloud (copying the fixed
#: splats, SplatCloud.validate of the result): validate 0.11-0.18 s and the
#: copies 0.04 s for 1M splats
EDITOR_COMMIT_US_PER_SPLAT = 0.2
#: estimated commit cost per Gaussian of the support (J Sigma J^T
#: re-decomposed by SVD, SH bands 1-3 rotated): 0.63-0.97 s for 33k of a
#: 100k scene (SH degree 3)
EDITOR_COMMIT_US_PER_SUPPORT_GAUSSIAN = 25.0
#: Gaussians per chunk of a commit's covariance / SH work (the progress the
#: editor shows between chunks; the result is bitwise the same for any
#: chunk).  33k Gaussians of a 100k scene, SH degree 3, two rounds each:
#: one block 0.39 / 0.34 s, 4096 0.33 / 0.31 s, 8192 0.34 / 0.41 s, 16384
#: 0.35 / 0.44 s (loaded machine: no cost measurable; 4096 gives ~8 steps)
GAUSSIAN_COMMIT_CHUNK = 4096


# ---------------------------------------------------------------------------
# Editor UX fixes (issue 10: the side panel's pinned footer)
# ---------------------------------------------------------------------------
#: lines the side panel's footer keeps for the status line even when it is
#: shorter or gone, so the sections above do not jump as messages come and
#: go: at EDITOR_GUI_PANEL_WIDTH most messages ("saved bunny-edited.ply and
#: ...", "distortion heat map on: ...") wrap to 1-2 lines; a long path (4
#: lines in a pytest tmp folder) grows the footer for that message only
EDITOR_GUI_FOOTER_MESSAGE_LINES = 2
#: ImGui lays out in float pixels; two layout heights (or a widget edge and
#: its window's edge) closer than this are the same (the widget rects in the
#: status file are whole pixels)
EDITOR_GUI_LAYOUT_SLACK_PX = 0.5


# ---------------------------------------------------------------------------
# Gaussian level of detail while moving (splatedit.model.gaussian_lod, the
# editor's Viewport).  Sweeps recorded in docs/PERFORMANCE.md "Gaussian level
# of detail while moving": 960x600, importance subsets of the bundled bunny
# (5,000) and of unit-sphere scenes (200k, 1M; splatedit.bench.gs_scenes).
# ---------------------------------------------------------------------------
#: the largest level holds this share of the scene (ranked by importance):
#: 1M Gaussians on lavapipe draw 250k in ~1 s, far over any interactive
#: budget, so larger levels are never chosen there
GS_LOD_MAX_FRACTION = 0.25
#: ... but at least this many Gaussians (the whole scene when smaller), and no
#: level is drawn with fewer (a 5,000-Gaussian bunny at 200: mean difference 5.2/255)
GS_LOD_MIN_COUNT = 2_000
#: the kept Gaussians' standard deviations are drawn (total importance / kept
#: importance) ** this times larger.  Mean per-pixel max-channel difference to
#: the full frame (1/255), 4% kept: bunny 5.2 / 5.9 / 6.7 with 0.5 / 0.35 /
#: 0.25, 200k sphere 5.8 / 7.5 / 9.0; no compensation at 1M, 4%: 9.1, with 0.5: 4.0
GS_LOD_COVER_EXP = 0.5
#: ... but at most this factor: the cost of a Gaussian grows with its screen
#: area (factor squared), so an uncapped factor makes fewer Gaussians no
#: cheaper (a tester's 1M tiled-bunny scene in the window: 2,000 Gaussians
#: at sigma x22 took 240 ms at half resolution, the budget kept shrinking
#: the count to the minimum and the image became a few giant blobs)
GS_LOD_MAX_COMPENSATION = 3.0
#: a level is drawn at full resolution only when the budget fits at least this
#: many Gaussians (else at half resolution, as point models' coarsest level):
#: at 1M, 4% (40k) kept gives a mean difference of 4.0/255, 10% 3.5, 25% 2.5
GS_LOD_PREFER_COUNT = 40_000
#: cost guess per Gaussian (ms) before the first full frame is measured
#: (docs/PERFORMANCE.md: 1M Gaussians ~4 s a frame on lavapipe, 100k ~0.5 s)
GS_LOD_GUESS_MS_PER_GAUSSIAN = 0.004
#: the LOD's image against the full frame in tests: mean per-pixel
#: max-channel difference (1/255) at most this, with the level's Gaussians a
#: quarter or a tenth of the scene, compensated.  Measured at 240x180: bunny
#: 25% 3.43 (4.76 uncompensated), 100k sphere 10% 5.20 (7.57); the editor
#: bench at 1280x720 (16k of 1M at half resolution): 4.92
GS_LOD_TEST_MEAN_DIFF = 6.5


# ---------------------------------------------------------------------------
# The status line's hint for a view that draws (almost) nothing (app/view/coverage.py)
# ---------------------------------------------------------------------------
#: hint when the bound of the drawn share of the view is below this ...
EDITOR_COVERAGE_HINT_SHARE = 0.005
#: ... while at least this many splat centres are in view
EDITOR_COVERAGE_HINT_MIN_IN_VIEW = 500
#: splats looked at by the estimate (a fixed stride of the cloud)
EDITOR_COVERAGE_SAMPLE = 16_384


# ---------------------------------------------------------------------------
# The live G / R / S readout next to the cursor (app/tools/gizmo.py readout_box)
# ---------------------------------------------------------------------------
#: its box keeps at least this far from the window's edges (pixels): a tester
#: found it touching the right edge with the cursor there
EDITOR_READOUT_MARGIN_PX = 8
#: its box's top-left corner from the cursor (pixels), right and down
EDITOR_READOUT_OFFSET_PX = 18


# ---------------------------------------------------------------------------
# Out-of-core documents: large COPC scans (app/document/outofcore.py)
# ---------------------------------------------------------------------------
#: a COPC file with more points than this opens out of core (an octree level of
#: detail; a smaller one is read whole like any LAZ): at ~110 B per splat in the
#: editor (positions, axes, colours, selection, graph) 3M points are ~330 MB
EDITOR_OOC_MIN_POINTS = 3_000_000
#: another scan file larger than this (bytes) is converted once into a COPC cache
#: (io.copc.cached_copc) and opened out of core
EDITOR_OOC_CONVERT_BYTES = 1 << 30
#: points of the first view (the coarse top of the octree, loaded before the
#: first frame): per-node normals took ~9 us per point on 2 loaded cores, so
#: 200k is ~2 s of the 10 s open-to-first-frame goal
EDITOR_OOC_FIRST_POINTS = 200_000
#: points shown after refinement where the camera looks: the editor draws 1M
#: splats at 21-45 fps moving (levels of detail) on lavapipe (PERFORMANCE.md,
#: "Editor frame rate"); 800k leaves room for a full-resolution edit region
EDITOR_OOC_POINT_BUDGET = 800_000
#: a document with edits or a selection only ever adds nodes (indices stay
#: valid for the history); it stops refining at this many points
EDITOR_OOC_MAX_POINTS = 2_500_000
#: the view is refined this long after the camera stopped (seconds)
EDITOR_OOC_SETTLE_S = 0.3
#: the full-resolution region around a painted support: its bounding box
#: grown by this many of the painted splats' largest radius (so the
#: selection's rim, transferred to the finer points by nearest neighbour,
#: is loaded whole)
EDITOR_OOC_REGION_MARGIN_RADII = 2.0
#: most points a support's full-resolution region may add to the document: a
#: larger support cannot be edited (moves wait; the panel says to paint less):
#: editing only its shown points would leave the file's other points behind
EDITOR_OOC_REGION_MAX_POINTS = 2_000_000
#: points read per batch (a progress step, a cancellation point)
EDITOR_OOC_READ_BATCH = 250_000

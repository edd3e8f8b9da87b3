"""Tolerances and tuning constants of the Vulkan renderers: splats, pre-pass, GUI pass, Gaussians, progressive frames (splatedit.render).

Part of :mod:`splatedit.tolerances` (import them from there); every value
carries the measurement behind it.
"""


# --- rendering (splatedit.render) -------------------------------------------
#: EWA screen-space low-pass filter radius in pixels (sqrt(2)/2): every splat covers at
#: least the disc of this radius around its projected centre (Botsch, Hornung,
#: Zwicker, Kobbelt 2005: r^2 = min(r_object^2, r_screen^2))
RENDER_LOWPASS_RADIUS_PX = 0.7071
#: Gaussian splat weight exp(-k r^2), r^2 <= 1 (k = 2: weight 0.135 at the rim)
RENDER_GAUSS_SHARPNESS = 2.0
#: visibility pass pushes splats back along the view ray by this many splat
#: radii (max(|u'|, |v'|)); splats within it are blended in the attribute pass
RENDER_VISIBILITY_EPS_RADII = 1.0
#: accumulated weight below this is background
RENDER_MIN_WEIGHT = 1e-3
#: near/far planes chosen from the model bounds: bounding-sphere depth range,
#: widened by this fraction of the sphere radius on each side
RENDER_CLIP_MARGIN_REL = 0.05
#: near plane is at least far * this (keeps float depth precision usable)
RENDER_NEAR_FAR_RATIO = 1e-3
#: Camera: |forward x up| <= this * |forward| |up| (sine of their angle) means
#: the up hint is parallel to the view direction
RENDER_CAMERA_MIN_UP_SINE = 1e-12
#: Camera.clip_range: the bounding-sphere radius is at least this times
#: max(1, eye distance), so that a single point still gets near < far
RENDER_CLIP_MIN_RADIUS_REL = 1e-12
#: Camera.frame: distance so that the bounding sphere fits the view, times this
RENDER_FRAME_MARGIN = 1.05
#: default vertical field of view, degrees
RENDER_FOV_DEG = 40.0
#: `splatedit render` draws a level of detail when many splats fall in one
#: pixel: splats thinned at random and enlarged to about this radius in
#: pixels (splatedit.render.splat.headless.pixel_level; --full draws every one).
#: Against the full render (lavapipe, raster path), a 2M-splat bunny surface
#: (float32 normals + radius, data_tools/make_large_model.py --normals-radius)
#: at 640x360, RGB levels: min radius 0.5 px keeps 53 % of the splats, mean
#: |difference| 0.054, 0.040 % of the pixels off by more than 8 levels;
#: 0.75 px: 24 %, 0.120, 0.19 %; 1 px: 13 %, 0.161, 0.33 % (0.169, 0.38 %
#: with the margin below); 1.5 px: 6 %, 0.23, 0.52 %; 2 px: 3 %, 0.28,
#: 0.62 %.  The 10M-splat file at 1280x720: 11 % kept, 0.089, 0.095 %
#: (the whole `splatedit render` 38.4 s -> 8.2 s, see docs/PERFORMANCE.md)
RENDER_LOD_MIN_RADIUS_PX = 1.0
#: ... only when the level keeps at most this share of the splats
RENDER_LOD_MAX_KEPT_SHARE = 0.5
#: the thinned splats' linear size is multiplied by up to this margin (1 for
#: kept-with-certainty splats, this for the strongly thinned ones): random
#: thinning leaves Poisson gaps; with 1.0 the 2M bunny at 640x360 had 3
#: pinholes (background pixels inside the silhouette; the full render 0) and
#: the 10M at 1280x720 14; with 1.2 none (1.4: none, 0.424 % of the pixels
#: off by more than 8 levels against 0.375 %)
RENDER_LOD_MARGIN = 1.2
#: the draw path of `splatedit render`'s level of detail (one frame: the
#: "auto" path would draw two more to measure both).  The 10M file's level
#: (1.06M splats about a pixel wide, 1280x720, lavapipe, load 5): compute
#: 0.61 s of GPU time, raster 1.31 s; "auto" 3.8 s for its probe and frame.
#: Where the device cannot run the compute path the raster path draws it
RENDER_LOD_PATH = "compute"
#: gamma applied by the shading pass (sRGB-like output)
RENDER_GAMMA = 2.2
#: headlight Phong: ambient, diffuse, specular, shininess
RENDER_LIGHT = (0.2, 0.8, 0.25, 32.0)
#: default material (sRGB 0..255) for clouds without colours
RENDER_DEFAULT_COLOR = (200, 200, 205, 255)
#: background (sRGB 0..1, written as is)
RENDER_BACKGROUND = (1.0, 1.0, 1.0)
#: selection tints (linear rgb, mix strength): the paper's blue support and
#: green handle (Botsch & Kobbelt 2005, Fig. 1)
RENDER_TINT_SUPPORT = (0.15, 0.3, 1.0, 0.55)
RENDER_TINT_HANDLE = (0.1, 0.8, 0.15, 0.7)
#: deformation basis columns: any count 1..this (zero-padded to groups of 4 on
#: the GPU; 16 columns = 16 vertex attributes + 5 of lavapipe's 32, dC in a
#: 192-byte uniform block)
RENDER_MAX_BASIS_COLUMNS = 16
#: splats whose footprint (projected ellipse and low-pass disc) lies within this
#: many pixels of the projected centre along x and y (and, beyond 1 pixel, with
#: an x/y extent ratio <= 2) are drawn as one square POINT_LIST point of side
#: 2 * extent through the same EWA fragment shader: the same pixels as the
#: quad, hence hole-free, for one vertex instead of a 4-vertex strip.
#: Measured at 1280x720 (lavapipe): 1M-splat sphere 1.5x faster than all
#: quads, 100k 1.3x faster with 3 px than with 1 px
RENDER_POINT_SPLAT_MAX_PX = 3.0


# ---------------------------------------------------------------- GUI (Dear ImGui on Vulkan)
#: largest difference (8-bit levels, any channel) between a flat GUI area drawn
#: by the GUI pipeline on lavapipe and the same colour alpha-blended in float
#: from ImGui's 8-bit style colour over the 8-bit background.  Measured
#: (tests/render/test_gui.py): 0 for the opaque window background, 0.4 for the
#: translucent button colour (alpha 0.40: UNORM rounding of the blend); 2
#: leaves a level of slack for other drivers' blend rounding
GUI_COLOUR_TOL = 2
#: a pixel is a glyph pixel when its brightness (mean of RGB) exceeds the
#: window background's by this many levels.  Measured: ImGui's default font
#: (13 px ProggyClean, white) over the 46-level window background gives 255 in
#: glyph pixels and the background elsewhere ("Hello splats": 153 pixels above
#: +10 and the same 153 above +60); 60 stays robust to antialiased fonts
GUI_TEXT_CONTRAST = 60


# --- Gaussian splatting rendering (issue 13, part 2) ------------------------
#: screen-space low-pass dilation added to every projected 2D covariance
#: (pixels^2): the 3DGS reference implementation's 0.3 (Kerbl et al. 2023),
#: which keeps sub-pixel Gaussians at least ~0.55 px wide (anti-aliasing)
GS_LOWPASS_PX2 = 0.3
#: per-fragment alpha ceiling and floor of the 3DGS image formation: alpha is
#: clamped at 0.99 (no Gaussian is fully opaque, keeps 1 - alpha > 0) and a
#: fragment below 1/255 contributes nothing (it is skipped; it cannot change
#: an 8-bit pixel on its own).  Both from the reference rasteriser
GS_ALPHA_MAX = 0.99
GS_ALPHA_MIN = 1.0 / 255.0
#: blending stops where the transmittance would drop below this (3DGS: 1e-4);
#: what follows changes a pixel by less than 1e-4 of full scale (0.03 of an
#: 8-bit step)
GS_MIN_TRANSMITTANCE = 1e-4
#: (tile, Gaussian) pairs per Gaussian the compute tile rasterizer's buffers
#: hold at first (gaussian/tiles.py; a frame that wants more grows them and is drawn
#: again).  Measured: the bench's sphere scenes at 1280x720 want 2.3 (100k
#: Gaussians) per Gaussian, the bundled bunny at 160x120 2.1
GS_TILE_PAIRS_PER_GAUSSIAN = 4.0
#: the 3DGS Jacobian clamps the view ray's x/z and y/z at this factor times the
#: half field of view's tangent, so Gaussians far outside the frustum do not
#: get unbounded screen covariances
GS_FRUSTUM_CLAMP = 1.3
#: Gaussians whose centre is nearer than this fraction of the near plane
#: distance are culled (3DGS culls at view depth 0.2 in its scene units; our
#: near plane comes from the model bounds, so the cut is relative to it)
GS_NEAR_CULL_REL = 1.0
#: a Gaussian is pickable when its opacity is at least this: 3DGS scenes carry
#: many near-transparent "floaters" (opacity < 0.1 is common after training)
#: that a click should pass through to the surface behind them
GS_PICK_MIN_OPACITY = 0.2
#: the pick footprint is the ellipse of this Mahalanobis radius (sigmas): at 2
#: sigma a Gaussian of opacity 1 still has alpha 0.135, so the picked pixel
#: visibly belongs to it; the drawn footprint (alpha >= 1/255) reaches 3.33
GS_PICK_SIGMAS = 2.0
#: Vulkan image vs the numpy reference rasteriser (tests/render/test_gaussians.py):
#: largest allowed mean |difference| over RGB in 8-bit steps, and the largest
#: allowed share of pixels off by more than GS_REF_PIXEL_TOL steps.  Measured
#: at 96x72 (1500 Gaussians on the bunny, 4 views; 400 random anisotropic ones,
#: SH degree 0-3; the GPU-deformed bunny): mean 0.03-0.14 (0.21 on the scene
#: pixels alone), worst pixel 2 steps (float32 vs float64 projection,
#: half-float SH bands 1-3, RGBA16F blending); a wrong SH frame (no rotation)
#: gives 2.9-15 on the scene pixels.  The limits leave 7x headroom on the mean
GS_REF_MEAN_TOL = 1.0
GS_REF_PIXEL_TOL = 16
GS_REF_BAD_SHARE = 0.01
#: polar decomposition on the GPU (rotation of J for the SH view direction):
#: Newton iterations R <- (R + R^-T) / 2 from R = J; converges quadratically
#: once the singular values are near 1, each early step halves a large one:
#: 12 reaches float32 precision for stretches up to 100x
GS_POLAR_ITERATIONS = 12


# ---------------------------------------------------------------------------
# Windowed compute pre-pass (renderer, clouds above one storage binding)
# ---------------------------------------------------------------------------
#: splats per pre-pass window when the whole cloud's records (48 bytes per
#: splat) or geometry do not fit one storage binding (lavapipe's
#: maxStorageBufferRange is 128 MiB: 2,796,202 splats of records).  Measured
#: on `splatedit render` of a 10M sphere at 1280x720 (2 cores, load 2.1-2.3,
#: two rounds): 2^21 splats 9.4 / 12.0 s, 1.71 / 1.68 GB peak; 2^20 8.5 / 9.3 s,
#: 1.63 / 1.64 GB; 2^19 8.6 / 9.1 s, 1.55 / 1.56 GB.  2^20 keeps the records
#: at 48 + 32 MiB and is a multiple of every basis window (524,288 splats at
#: 16 columns) and of any offset alignment; the device limit caps it too
RENDER_PREPASS_WINDOW_SPLATS = 1 << 20


# ---------------------------------------------------------------------------
# Progressive refinement by default: chunks composed on the device (issue 10 "one device", issue 11 part 5)
# ---------------------------------------------------------------------------
#: chunk steps the work budget of one presented frame is split into (the chunk is
#: sized to budget / this; a step that leaves room for another is followed by one).
#: One: every step pays a fixed cost (a render pass loading and storing the full-size
#: depth and accumulation targets, the pre-pass dispatch, a submit): 1M splats at
#: 1280x720 drawn in 20k-splat chunks took 2.9-4.0 s, in 250k chunks 1.16 s
#: (docs/PERFORMANCE.md, 2 loaded cores), i.e. ~20-30 ms per step; 3 steps per
#: frame gave 66-77 steps per 1M refinement in the window
EDITOR_PROGRESSIVE_STEPS_PER_FRAME = 1
#: a colour step's cost per splat over a visibility step's (the chunk is divided by
#: it when the colour half starts), 100k-splat steps of 1M splats at 1280x720, draw
#: only: 35 vs 32 ms at load 0.5 (53 ms with the old per-step shading pass of 16 ms
#: and readback), 128 vs 106 and 184 vs 170 ms at load 10 (2 cores): 1.1-1.2
EDITOR_PROGRESSIVE_ATTR_COST = 1.15
#: share of the frame interval left to the steps at least, however slow presenting
#: is (the rest is the measured present + GUI cost and the composition pass)
EDITOR_PROGRESSIVE_MIN_WORK_SHARE = 0.5
#: pixels added around the projected boxes of the splats drawn since the last shown
#: image: the shading pass of :meth:`ProgressiveFrame.show` covers only that rect.  A
#: splat's quad bounds its ellipse and the low-pass disc (RENDER_LOWPASS_RADIUS_PX =
#: 0.71 px); point splats are at most a few pixels wide but centred on the splat;
#: 2 px covers both and the rounding (tests/render/test_progressive.py compares the
#: composed images with the whole-image CPU composite bit for bit)
PROGRESSIVE_SHADE_PAD_PX = 2.0
#: the compute tile rasterizer's image vs the quad path's (tests/render/test_gs_tiles.py):
#: largest mean |difference| over RGB and largest single difference, in 8-bit
#: steps, per accumulator format.  Measured on the bundled 5,000-Gaussian bunny
#: and 2,000 random anisotropic Gaussians, 4 views each at 96x72 and 257x131:
#: RGBA16F mean 0.04-0.18, worst 3 (the quad path rounds the sum to half float
#: after every blend, the tile path once); RGBA32F mean 0.0006-0.005, worst 1
#: (float32 rounding; the tile path stops at GS_MIN_TRANSMITTANCE, the quad
#: path never).  The limits leave 2x headroom on the mean
GS_TILE_MEAN_TOL = {"rgba16f": 0.35, "rgba32f": 0.01}
GS_TILE_MAX_TOL = {"rgba16f": 4, "rgba32f": 1}
#: largest |coordinate| of a camera's eye and target (model units): the
#: default view of a model at the MAX_COORDINATE_ABS limit (a sphere of
#: radius 1e15 at 40 degrees) puts the eye 3.1e15 away, and a user's eye
#: may stand farther still.  1000x the model limit: float64 keeps 1e15-unit
#: model detail at 1e18 to 1/8 unit (ulp 128 over a 1e15 body), the GPU sees
#: the camera divided by the model's scale
RENDER_CAMERA_MAX_ABS = 1e18
#: the GPU's float32 coordinates are centred and scaled on the main body
#: instead of the full box when the full box is more than this many times the
#: body across (a sample's 1-99% box): float32 keeps 1e-7 of the offset from
#: the centre, so a body 1e-3 of the box across still has 1e-4 of itself in
#: resolution; a scan with one glitch point 1e9 away (ratio 1e9) rendered as
#: a vertical strip before
RENDER_GPU_BODY_RATIO = 1e3
#: points of the strided sample behind that test (a few ms at 10M splats)
RENDER_GPU_BODY_SAMPLE = 65536

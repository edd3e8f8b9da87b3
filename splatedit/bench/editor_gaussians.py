"""Editor frame times of a 3D Gaussian Splatting scene, still and moving
(``splatedit bench gaussian-editor``).

Per Gaussian count: Gaussians (SH degree 3) on the splats of a
Fibonacci-sampled unit sphere (:func:`splatedit.bench.gs_scenes.gaussians_from_splats`,
the renderer benchmark's scene) opened as an editor document, framed as the
editor frames a model, a ball support of ~20k Gaussians with a handle,
through the editor's :class:`~splatedit.app.view.viewport.Viewport`:

* ``still_ms``: the full frame (every Gaussian, full resolution);
* ``orbit_before_ms``: a moving frame without the level of detail (what
  every frame cost before it: all Gaussians);
* ``rank_s``: building the ranking (:func:`build_gaussian_lod`, the
  editor's background job);
* ``orbit_ms`` / ``drag_ms``: moving frames with it (camera orbiting; the
  handle dragged, a new dC each frame, the LOD Gaussians deformed on the
  GPU), median of the second half (after the budget adapted), with the
  Gaussians drawn and the resolution divisor;
* ``refine_s`` / ``refine_frames`` / ``refine_step_ms_max`` /
  ``refine_frame_ms_median``: the full frame after motion refined in chunks
  (:class:`~splatedit.app.view.progressive_refine.ProgressiveRefinement` with the
  Gaussian chunked frame, as the editor does): seconds to the full frame,
  presented frames meanwhile, the longest step (the sort) and the median
  frame's work (the window handles input between them);
* ``lod_mean_diff`` / ``lod_pixels_over_32``: the moving frame against the
  still frame of the same view (mean per-pixel max-channel difference in
  1/255, share of pixels differing by more than 32);
* ``loadavg_1min``.  Validation is off.
"""

from __future__ import annotations

import os
import time
from typing import Iterator

import numpy as np


def _diff(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    d = np.abs(a[..., :3].astype(np.int16) - b[..., :3].astype(np.int16)).max(axis=2)
    return round(float(d.mean()), 2), round(float((d > 32).mean()), 4)


def bench_gaussian_editor_frames(counts=(100_000, 1_000_000), size=(1280, 720), frames: int = 8,
                                 budget_ms: float = 100.0) -> Iterator[dict]:
    from splatedit.bench.editor import support_and_handle
    from splatedit.app.view.camera_control import OrbitCamera
    from splatedit.app.document.gaussian import gaussian_document
    from splatedit.app.view.viewport import Viewport
    from splatedit.bench.gs_scenes import gaussians_from_splats
    from splatedit.bench.render import sphere_cloud
    from splatedit.deform.basis import DeformationBasis
    from splatedit.model.gaussian_lod import build_gaussian_lod
    from splatedit.render.splat.renderer import Renderer

    w, h = size
    for n in counts:
        n = int(n)
        g = gaussians_from_splats(sphere_cloud(n, overlap=1.0), seed=0)
        doc = gaussian_document(g)
        vp = Viewport(budget_ms=budget_ms, renderer=Renderer(validation=False))
        try:
            vp.set_cloud(doc)
            sup, hnd = support_and_handle(doc)
            vp.set_selection(sup, hnd, 1)
            from splatedit.select.closure import closed_masks
            sup, hs, _ = closed_masks(doc, sup, [hnd])
            basis = DeformationBasis.fit(doc, sup, hs)
            vp.set_basis(basis)
            vp.set_dc(None)
            cam = OrbitCamera(scene_radius=doc.diagonal / 2, yaw=0.3, pitch=0.2)
            lo, hi = doc.bounds()
            cam.frame((lo + hi) / 2, doc.diagonal / 2, w / h)
            vp.render(cam, w, h)                          # upload + warm-up
            still = []
            for _ in range(2):
                full = vp.render(cam, w, h)
                still.append(vp.last_info.ms)
            vp.render(cam, w, h, interactive=True)
            before = vp.last_info.ms
            t0 = time.perf_counter()
            lod = build_gaussian_lod(g)
            rank_s = time.perf_counter() - t0
            vp.set_gaussian_lod(lod)
            moving = vp.render(cam, w, h, interactive=True)        # first LOD frame: upload, adapts
            for _ in range(3):
                moving = vp.render(cam, w, h, interactive=True)
            mean_diff, over = _diff(moving, full)
            orbit, info = [], None
            for k in range(frames):
                cam.orbit(15, 0)
                vp.render(cam, w, h, interactive=True)
                orbit.append(vp.last_info.ms)
                info = vp.last_info
            drag = []
            for k in range(frames):
                m = np.eye(4)
                m[:3, 3] = np.array([0.0, 1.0, 0.5]) * 0.02 * (k + 1) * doc.diagonal
                vp.set_dc(basis.displacement([m]))
                vp.render(cam, w, h, interactive=True)
                drag.append(vp.last_info.ms)
            vp.set_dc(None)
            from splatedit.app.view.progressive_refine import ProgressiveRefinement
            vp.render(cam, w, h, interactive=True)
            under = vp.render(cam, w, h, interactive=True)
            chunk = max(1000, int(budget_ms / 2 / max(vp.ms_per_splat, 1e-9)))
            pr = ProgressiveRefinement(vp.progressive(cam, w, h, chunk), None, under, budget_ms, False)
            while not pr.done:
                pr.advance()
                pr.frame_done(pr.work_ms[-1] + pr.show_ms[-1])
            refined = pr.image
            pr.close()
            ref_diff = _diff(refined, vp.render(cam, w, h))[0]
            half = frames // 2
            yield {"bench": "gaussian_editor", "gaussians": n, "width": w, "height": h, "budget_ms": budget_ms,
                   "still_ms": round(float(np.median(still)), 1), "orbit_before_ms": round(before, 1),
                   "rank_s": round(rank_s, 3), "lod_levels_max": lod.m,
                   "orbit_ms": round(float(np.median(orbit[half:])), 1),
                   "drag_ms": round(float(np.median(drag[half:])), 1),
                   "moving_gaussians": info.splats, "moving_divisor": info.div,
                   "still_over_orbit": round(float(np.median(still)) / float(np.median(orbit[half:])), 1),
                   "refine_s": round(pr.done_s, 2), "refine_frames": len(pr.work_ms),
                   "refine_step_ms_max": round(max(pr.step_ms), 1),
                   "refine_frame_ms_median": round(float(np.median(pr.work_ms)), 1),
                   "refined_vs_full_mean_diff": ref_diff,
                   "lod_mean_diff": mean_diff, "lod_pixels_over_32": over,
                   "loadavg_1min": round(os.getloadavg()[0], 2)}
        finally:
            vp.close()

"""Editor frame times while idle and while dragging, for large models.

``bench_editor_frames`` yields one dict per splat count.  Scene: the bundled
bunny mesh resampled to ``n`` surface splats (uniform on the area, splat
radius from the sampling density, ~2x overlap), framed in a 1280x720 view as
the editor frames a model.  For each count it measures, through the editor's
:class:`~splatedit.app.view.viewport.Viewport` (renderer + levels of detail):

* ``idle_ms``: the full-quality frame (all splats, full resolution);
* ``drag_ms``: frames while the handle is dragged (a new ``dC`` each frame,
  interactive mode: level of detail / reduced resolution chosen to fit the
  budget);
* ``orbit_ms``: frames while the camera orbits (interactive mode);
* ``compose_ms``: overlay compositing of one frame (CPU), to add to the above
  with the ~2-5 ms of the swapchain copy and present;
* with ``presentation=True`` (default) the presentation cost of an idle
  frame on the readback path and on the GUI's GPU path, same run
  (:mod:`splatedit.bench.present`: ``present_cpu_ms``,
  ``present_gpu_ms``, their ratio and the whole frames);
* the level used while moving, the LOD build time and the basis fit time;
* with ``rigs=True`` (default) also ``drag4h_ms`` (four handles at once: a
  16-column basis, all columns drawn with a new dC per frame) and
  ``drag_curve16_ms`` (a 16-point control curve: 16 columns), with their fit
  times and the full-quality frame ``idle16_ms`` with the 16-column basis.

Validation is off (it adds per-call overhead unrelated to the editor).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Iterator

import numpy as np

from splatedit.model.cloud import SplatCloud


def bunny_surface_cloud(n: int, seed: int = 0, overlap: float = 2.0) -> SplatCloud:
    """``n`` splats sampled uniformly on the bundled bunny mesh."""
    from splatedit.data import default_model_path
    from splatedit.io import read
    mesh = read(default_model_path())
    v, f = mesh.positions, mesh.faces
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    cr = np.cross(b - a, c - a)
    area = 0.5 * np.linalg.norm(cr, axis=1)
    rng = np.random.default_rng(seed)
    tri = rng.choice(len(f), size=n, p=area / area.sum())
    r1 = np.sqrt(rng.random(n))
    r2 = rng.random(n)
    p = (1 - r1)[:, None] * a[tri] + (r1 * (1 - r2))[:, None] * b[tri] + (r1 * r2)[:, None] * c[tri]
    nrm = cr[tri] / np.linalg.norm(cr[tri], axis=1, keepdims=True)
    t1 = np.cross(nrm, np.where(np.abs(nrm[:, [0]]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(nrm, t1)
    r = np.sqrt(overlap * area.sum() / (np.pi * n))
    return SplatCloud(p, t1 * r, t2 * r, None, name=f"bunny{n}")


def support_and_handle(cloud: SplatCloud, support_splats: int = 20000):
    """A ball support of about ``support_splats`` splats around a surface point
    and a handle ball of a quarter of its radius."""
    p = cloud.positions
    guess = p[np.argmax(p[:, 1])] * 0.6 + p.mean(0) * 0.4
    centre = p[np.argmin(np.linalg.norm(p - guess, axis=1))]     # a surface point
    d = np.linalg.norm(p - centre, axis=1)
    k = min(support_splats, cloud.n // 4)
    r = float(np.partition(d, k)[k])
    sup = d <= r
    hnd = d <= r / 4
    return sup, hnd


def _rigs(cloud: SplatCloud, sup: np.ndarray, hnd: np.ndarray):
    """Four small handle balls and a 16-point curve inside the support."""
    p = cloud.positions
    ids = np.flatnonzero(sup)
    c = p[hnd].mean(0)
    d = p[ids] - c
    r = float(np.linalg.norm(d, axis=1).max())
    _, _, vt = np.linalg.svd(d - d.mean(0), full_matrices=False)
    e1, e2 = vt[0], vt[1]
    handles = []
    for a in (e1, -e1, e2, -e2):
        q = ids[np.argmin(np.linalg.norm(p[ids] - (c + 0.55 * r * a), axis=1))]
        handles.append(sup & (np.linalg.norm(p - p[q], axis=1) <= r / 7))
    # in the support's tangent plane (a curve need not lie on the surface)
    t = np.linspace(-0.65, 0.65, 16)[:, None]
    pts = c + t * r * e1 + 0.15 * r * np.sin(5 * t) * e2
    return handles, pts


def _drag_frames(vp, cam, w, h, basis, frames, scale):
    out = []
    vp.render(cam, w, h, interactive=True)
    rng = np.random.default_rng(0)
    for k in range(frames):
        vp.set_dc(rng.normal(size=(basis.n_columns, 3)) * scale * (k + 1) / frames)
        vp.render(cam, w, h, interactive=True)
        out.append(vp.last_info.ms)
    return round(float(np.median(out)), 1)


def bench_editor_frames(counts=(100_000, 1_000_000, 2_000_000), size=(1280, 720), frames: int = 6,
                        budget_ms: float = 100.0, progress=None, rigs: bool = True,
                        presentation: bool = True) -> Iterator[dict]:
    from splatedit.app.ui import overlay as ov
    from splatedit.app.view.camera_control import OrbitCamera
    from splatedit.app.view.viewport import Viewport
    from splatedit.deform.basis import DeformationBasis
    from splatedit.model.lod import LodPyramid
    from splatedit.render.splat.renderer import Renderer

    w, h = size
    renderer = Renderer(validation=False)
    vp = Viewport(budget_ms=budget_ms, renderer=renderer)
    try:
        for n in counts:
            n = int(n)
            cloud = bunny_surface_cloud(n)
            t0 = time.perf_counter()
            pyr = LodPyramid(cloud)
            lod_s = time.perf_counter() - t0
            vp.set_cloud(cloud)
            vp.set_pyramid(pyr)
            vp.assume_cost(None, 1)
            sup, hnd = support_and_handle(cloud)
            vp.set_selection(sup, hnd, n)
            cam = OrbitCamera(scene_radius=cloud.diagonal / 2, yaw=0.3, pitch=0.2)
            lo, hi = cloud.bounds()
            cam.frame((lo + hi) / 2, cloud.diagonal / 2, w / h)
            from splatedit.select.closure import closed_masks
            sup, (hnd,), _ = closed_masks(cloud, sup, [hnd])   # as the editor closes its strokes
            t0 = time.perf_counter()
            basis = DeformationBasis.fit(cloud, sup, [hnd])
            fit_s = time.perf_counter() - t0
            vp.set_basis(basis)
            vp.set_dc(None)
            vp.render(cam, w, h)                       # upload + warm-up
            idle = [vp.render(cam, w, h) is not None and vp.last_info.ms for _ in range(2)]
            present = {}
            if presentation:
                try:
                    from splatedit.bench.present import bench_presentation
                except ImportError:          # imgui-bundle missing: no GPU-path comparison
                    pass
                else:
                    vp.set_dc(None)
                    present = bench_presentation(vp, cam, w, h)
            # dragging the handle: a new dC every frame
            piv = cloud.positions[hnd].mean(0)
            drag, info = [], {}
            vp.render(cam, w, h, interactive=True)    # warm-up of the level's renderer
            for k in range(frames):
                m = np.eye(4)
                m[:3, 3] = np.array([0.0, 1.0, 0.5]) * 0.02 * (k + 1) * cloud.diagonal
                vp.set_dc(basis.displacement([m]))
                frame = vp.render(cam, w, h, interactive=True)
                drag.append(vp.last_info.ms)
                info = dataclasses.asdict(vp.last_info)
            tc = time.perf_counter()
            panel = ov.text_panel(tuple(f"line {i} of the status panel, 1234 ms" for i in range(9)))
            for p in (ov.Patch(8, 8, panel), ov.Patch(600, 300, ov.ring(24))):
                ov.blend(frame, p)
            compose = (time.perf_counter() - tc) * 1e3
            vp.set_dc(None)
            orbit = []
            for k in range(frames):
                cam.orbit(15, 0)
                vp.render(cam, w, h, interactive=True)
                orbit.append(vp.last_info.ms)
            del piv
            extra = {}
            if rigs:
                from splatedit.deform.curves import ControlCurve
                handles, pts = _rigs(cloud, sup, hnd)
                scale = 0.005 * cloud.diagonal
                sup4, handles, _ = closed_masks(cloud, sup, handles)
                t0 = time.perf_counter()
                b4 = DeformationBasis.fit(cloud, sup4, handles)
                extra["fit4h_s"] = round(time.perf_counter() - t0, 2)
                vp.set_basis(b4)
                vp.set_dc(None)
                vp.render(cam, w, h)
                vp.render(cam, w, h)
                extra["idle16_ms"] = round(vp.last_info.ms, 1)
                extra["drag4h_ms"] = _drag_frames(vp, cam, w, h, b4, frames, scale)
                del b4
                t0 = time.perf_counter()
                bc = DeformationBasis.fit(cloud, sup, [], curves=[ControlCurve.through(pts)])
                extra["fit_curve16_s"] = round(time.perf_counter() - t0, 2)
                vp.set_basis(bc)
                extra["drag_curve16_ms"] = _drag_frames(vp, cam, w, h, bc, frames, scale)
                vp.set_basis(None)
                vp.set_dc(None)
            yield {"case": "editor_frames", "splats": n, "width": w, "height": h,
                   "budget_ms": budget_ms,
                   "idle_ms": round(float(np.median(idle)), 1),
                   "drag_ms": round(float(np.median(drag)), 1),
                   "orbit_ms": round(float(np.median(orbit)), 1),
                   "drag_fps": round(1000.0 / float(np.median(drag)), 1),
                   "moving_splats": int(info.get("splats", n)), "moving_lod": bool(info.get("lod")),
                   "moving_resolution_divisor": int(info.get("div", 1)),
                   "lod_levels": [lvl.n for lvl in pyr.levels], "lod_build_s": round(lod_s, 2),
                   "support": int(sup.sum()), "handle": int(hnd.sum()),
                   "fit_s": round(fit_s, 2), "compose_ms": round(compose, 2), **present, **extra}
    finally:
        vp.close()


def main() -> None:  # pragma: no cover - manual runs
    import json
    import sys
    counts = [int(x) for x in sys.argv[1:]] or [100_000, 1_000_000, 2_000_000]
    for line in bench_editor_frames(counts):
        print(json.dumps(line), flush=True)


if __name__ == "__main__":  # pragma: no cover
    main()


def bench_editor_first_image(n: int, size=(1280, 720), frames: int = 4, budget_ms: float = 100.0,
                             full_frame_max: int = 2_000_000) -> dict:
    """What opening an ``n``-splat model costs before the first image, and the
    frame rate while moving, through the editor's :class:`Viewport`.

    ``first_image_s``: level-of-detail preview (``LodPyramid(background=True)``,
    as the editor builds it) + upload of the level + its first frame (the
    editor shows the level while the full-quality frame is drawn in the
    background), after the cloud is in memory (reading the file is ``bench
    io``'s); ``lod_all_levels_s``: until the real levels replaced the preview
    (about, as the orbit frames share the CPU); ``moving_fps``: orbiting
    frames (interactive: the level that fits ``budget_ms``, possibly still the
    preview); ``full_frame_s``: one full-quality frame (the background
    refinement; measured up to ``full_frame_max`` splats).
    """
    from splatedit.app.view.camera_control import OrbitCamera
    from splatedit.app.view.viewport import Viewport
    from splatedit.model.lod import LodPyramid
    from splatedit.render.splat.renderer import Renderer
    from splatedit.tolerances import EDITOR_GUESS_MS_PER_SPLAT

    w, h = size
    cloud = bunny_surface_cloud(int(n))
    vp = Viewport(budget_ms=budget_ms, renderer=Renderer(validation=False))
    try:
        t0 = time.perf_counter()
        vp.set_cloud(cloud)
        vp.assume_cost(EDITOR_GUESS_MS_PER_SPLAT, w * h)      # as the editor does on opening
        pyr = LodPyramid(cloud, background=True)             # as the editor: preview first
        lod_s = time.perf_counter() - t0
        vp.set_pyramid(pyr)
        cam = OrbitCamera(scene_radius=cloud.diagonal / 2, yaw=0.3, pitch=0.2)
        lo, hi = cloud.bounds()
        cam.frame((lo + hi) / 2, cloud.diagonal / 2, w / h)
        vp.render(cam, w, h, interactive=True)
        first = time.perf_counter() - t0
        first_splats = vp.last_info.splats
        ms = []
        for _ in range(frames):
            cam.orbit(15, 0)
            t1 = time.perf_counter()
            vp.render(cam, w, h, interactive=True)
            ms.append((time.perf_counter() - t1) * 1e3)
        t1 = time.perf_counter()
        pyr.wait()
        levels_s = lod_s + time.perf_counter() - t1 + sum(ms) / 1e3
        out = {"case": "editor_first_image", "splats": cloud.n, "width": w, "height": h,
               "first_image_s": round(first, 2), "lod_preview_s": round(lod_s, 2),
               "lod_all_levels_s": round(levels_s, 2),
               "first_image_splats": int(first_splats),
               "moving_fps": round(1000.0 / float(np.median(ms)), 1),
               "moving_splats": int(vp.last_info.splats),
               "moving_resolution_divisor": int(vp.last_info.div)}
        if cloud.n <= full_frame_max:
            t1 = time.perf_counter()
            vp.render(cam, w, h)
            out["full_frame_s"] = round(time.perf_counter() - t1, 2)
        return out
    finally:
        vp.close()

"""``splatedit bench WHAT``: run the benchmarks and yield one JSON-ready dict per case.

Every case compares the hot path with the obvious alternative in the same run
(LU vs IQR vs scipy; blocked QR vs scipy.linalg.qr vs a naive Householder QR;
EWA frame vs the one-pixel point-list floor; apply vs a plain copy).
Results are recorded in docs/PERFORMANCE.md.
"""

from __future__ import annotations

from typing import Iterator


def _solve(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    """The Table-1 cases, then the handle-to-first-frame grabs of
    :mod:`splatedit.bench.precompute` (``counts``: only grabs, of these
    support sizes, on clouds 2.5 times as large)."""
    from splatedit.bench.precompute import CASES, QUICK_CASES, bench_precompute
    from splatedit.bench.solve import bench_solve, standard_cases
    if counts:
        yield from bench_precompute([(int(2.5 * c), int(c)) for c in counts])
        return
    for name, cloud, support, handles in standard_cases(large=not quick):
        if quick and cloud.n > 300_000:
            continue
        out = {"bench": "solve"}
        out.update(bench_solve(cloud, support, handles, name=name))
        yield out
    yield from bench_precompute(QUICK_CASES if quick else CASES, gemm_size=1024 if quick else 4096)


def _groups(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    try:
        from splatedit.bench.solve import bench_groups
    except ImportError:
        return
    for line in bench_groups(quick=quick):
        yield {"bench": "groups", **line}


def _qr(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.qr import bench_qr
    for m in ((500, 1000) if quick else (1000, 3000, 5000)):
        yield {"bench": "qr", **bench_qr(m, repeat=1 if quick else 3)}


def _render(quick: bool, progress=None, counts=None, size=None, models=()) -> Iterator[dict]:
    from splatedit.bench.render import bench_render
    counts = counts or ((20_000, 100_000) if quick else (100_000, 1_000_000, 2_000_000))
    size = size or ((640, 360) if quick else (1280, 720))
    # both paths per case; the deformation cases hold a full basis: up to 2M splats
    yield from bench_render(counts=counts, size=size, models=models)
    from splatedit.bench.scale import bench_upload_lod
    for n in counts:
        yield {"bench": "render", **bench_upload_lod(int(n), size=size)}


def _gaussian_render(quick: bool, progress=None, counts=None, size=None, path=None) -> Iterator[dict]:
    from splatedit.bench.gs_render import bench_gaussians
    yield from bench_gaussians(counts=counts or ((20_000, 100_000) if quick else (100_000, 1_000_000)),
                               size=size or ((640, 360) if quick else (1280, 720)),
                               paths=(path,) if path else ("raster", "compute"))


def _gpu_sort(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.gs_sort import bench_gpu_sort
    yield from bench_gpu_sort(counts=counts or ((10_000, 100_000) if quick else (100_000, 1_000_000, 4_000_000)))


def _gaussian_editor(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    try:
        from splatedit.bench.editor_gaussians import bench_gaussian_editor_frames
    except ImportError:
        return
    yield from bench_gaussian_editor_frames(counts=counts or ((20_000, 100_000) if quick else (100_000, 1_000_000)),
                                            size=(640, 360) if quick else (1280, 720))


def _editor(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    try:
        from splatedit.bench.editor import bench_editor_frames
    except ImportError:
        return
    counts = counts or ((100_000,) if quick else (100_000, 1_000_000, 2_000_000))
    for line in bench_editor_frames(counts=[n for n in counts if n <= 2_000_000]):
        yield {"bench": "editor", **line}
    from splatedit.bench.editor import bench_editor_first_image
    for n in counts:
        yield {"bench": "editor", **bench_editor_first_image(int(n))}


def _closure(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.closure import bench_closure
    yield from bench_closure(counts=counts or ((20_000, 100_000) if quick else (100_000, 1_000_000)),
                             repeats=2 if quick else 3)


def _accuracy(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.accuracy import accuracy_cases, bench_accuracy
    for name, cloud, support, handles in accuracy_cases(large=False):
        if quick and cloud.n > 100_000:
            continue
        yield {"bench": "accuracy", **bench_accuracy(cloud, support, handles, name=name)}


def _detail(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.detail import bench_detail
    yield from bench_detail(sizes=((200, 200), (500, 500)) if quick else ((300, 300), (1000, 1000)))


def _gui(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.gui import bench_gui
    yield from bench_gui(size=(640, 360) if quick else (1280, 720), repeats=10 if quick else 30)


def _gaussians(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.gaussians import bench_gaussian_deform
    for n in counts or ((20_000, 100_000) if quick else (100_000, 1_000_000)):
        yield bench_gaussian_deform(n, repeat=1 if quick else 3)


def _estimate(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.estimate import bench_estimate
    for line in bench_estimate(counts or ((100_000,) if quick else (1_000_000,))):
        yield {"bench": "estimate", **line}


def _basis(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.basis import bench_basis
    counts = counts or ((100_000, 200_000) if quick else (1_000_000, 2_000_000, 5_000_000))
    yield from bench_basis(counts=counts, scipy_max=100_000 if quick else 1_000_000,
                           repeats=1 if quick else 3)


def _io(quick: bool, progress=None, counts=None, large: bool = False) -> Iterator[dict]:
    from splatedit.bench.io import bench_io
    yield from bench_io(quick=quick, large=large)


def _curves(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.trunk import cost, measure, trunk_edit
    from splatedit.deform.modes import DeformationMode
    edit = trunk_edit()
    for mode in (DeformationMode.LINEAR, DeformationMode.ROTATION):
        yield {"bench": "curves", **measure(*edit, mode)}
    yield {"bench": "curves", **cost(0.01 if quick else 0.005)}


def _batch(quick: bool, progress=None, counts=None) -> Iterator[dict]:
    from splatedit.bench.batch import bench_batch
    n = int(counts[0]) if counts else (20_000 if quick else 200_000)
    yield from bench_batch(5, 2, n)


#: the benchmark cases by name (`splatedit bench NAME`; "all" runs each in this order)
BENCHES = {
    "solve": _solve,
    "basis": _basis,
    "groups": _groups,
    "qr": _qr,
    "accuracy": _accuracy,
    "closure": _closure,
    "render": _render,
    "editor": _editor,
    "estimate": _estimate,
    "io": _io,
    "batch": _batch,
    "detail": _detail,
    "gui": _gui,
    "gaussians": _gaussians,
    "gaussian-render": _gaussian_render,
    "gpu-sort": _gpu_sort,
    "gaussian-editor": _gaussian_editor,
    "curves": _curves,
}


# --------------------------------------------------------------- tiny forms
# Every case's own code path on the smallest inputs it takes (seconds, not
# minutes): the tests run each one (tests/bench/test_bench_tiny.py) so that no
# benchmark breaks unnoticed (issue 19 item 8: ``bench editor --quick`` died
# with a TypeError nobody had run into).  The figures mean nothing at this size.

def _tiny_plane(n: int = 40):
    from splatedit.bench.solve import wavy_plane_cloud
    plane = wavy_plane_cloud(n)
    rad = __import__("numpy").linalg.norm(plane.positions[:, :2], axis=1)
    return plane, rad <= 0.6, [rad <= 0.2]


def _tiny_solve():
    from splatedit.bench.solve import bench_solve
    plane, sup, hs = _tiny_plane()
    yield {"bench": "solve", **bench_solve(plane, sup, hs, name="tiny", apply_repeats=1, fit_repeats=1)}


def _tiny_basis():
    from splatedit.bench.basis import bench_basis
    yield from bench_basis(counts=(3000,), scipy_max=3000, repeats=1)


def _tiny_groups():
    from splatedit.bench.solve import bench_groups, wavy_plane_cloud
    for line in bench_groups(wavy_plane_cloud(40), quick=True, apply_repeats=1, curve_points=(4,),
                             handle_counts=(2,)):
        yield {"bench": "groups", **line}


def _tiny_qr():
    from splatedit.bench.qr import bench_qr
    yield {"bench": "qr", **bench_qr(120, naive_max=120)}


def _tiny_accuracy():
    from splatedit.bench.accuracy import bench_accuracy
    plane, sup, hs = _tiny_plane()
    yield {"bench": "accuracy", **bench_accuracy(plane, sup, hs, name="tiny", tols=(1e-3,))}


def _tiny_closure():
    from splatedit.bench.closure import bench_closure
    yield from bench_closure(counts=(5000,), repeats=1)


def _tiny_render():
    from splatedit.bench.render import bench_render
    from splatedit.bench.scale import bench_upload_lod
    yield from bench_render(counts=(3000,), size=(96, 64), repeats=1, bunny=False)
    yield {"bench": "render", **bench_upload_lod(3000, size=(96, 64))}


def _tiny_editor():
    from splatedit.bench.editor import bench_editor_first_image, bench_editor_frames
    for line in bench_editor_frames(counts=(4000,), size=(96, 64), frames=2):
        yield {"bench": "editor", **line}
    yield {"bench": "editor", **bench_editor_first_image(4000, size=(96, 64), frames=2)}


def _tiny_estimate():
    from splatedit.bench.estimate import bench_estimate
    for line in bench_estimate((3000,), open3d=False):
        yield {"bench": "estimate", **line}


def _tiny_io():
    from splatedit.bench.io import bench_io
    yield from bench_io(counts=(3000,), las_points=2000)


def _tiny_batch():
    from splatedit.bench.batch import bench_batch
    yield from bench_batch(2, 1, 1500, ext=".xyz", workers=(2,), schedulers=("threads",), rounds=1)


def _tiny_detail():
    from splatedit.bench.detail import bench_detail
    yield from bench_detail(sizes=((40, 40),), repeats=1)


def _tiny_gui():
    from splatedit.bench.gui import bench_gui
    yield from bench_gui(size=(96, 64), repeats=2)


def _tiny_gaussians():
    from splatedit.bench.gaussians import bench_gaussian_deform
    yield bench_gaussian_deform(2000, repeat=1)


def _tiny_gaussian_render():
    from splatedit.bench.gs_render import bench_gaussians
    yield from bench_gaussians(counts=(2000,), size=(96, 64), repeats=1)


def _tiny_gaussian_editor():
    from splatedit.bench.editor_gaussians import bench_gaussian_editor_frames
    yield from bench_gaussian_editor_frames(counts=(2000,), size=(96, 64), frames=2)


def _tiny_gpu_sort():
    from splatedit.bench.gs_sort import bench_gpu_sort
    yield from bench_gpu_sort(counts=(3000,), repeats=1)


def _tiny_curves():
    from splatedit.bench.trunk import cost, measure, trunk_cloud, trunk_edit
    from splatedit.deform.modes import DeformationMode
    edit = trunk_edit(trunk_cloud(0.04))
    yield {"bench": "curves", **measure(*edit, DeformationMode.ROTATION)}
    yield {"bench": "curves", **cost(0.04, repeats=1)}


#: the tiny form of every case of BENCHES (same keys)
TINY = {"solve": _tiny_solve, "basis": _tiny_basis, "groups": _tiny_groups, "qr": _tiny_qr,
        "accuracy": _tiny_accuracy, "closure": _tiny_closure, "render": _tiny_render,
        "editor": _tiny_editor, "estimate": _tiny_estimate, "io": _tiny_io, "batch": _tiny_batch, "detail": _tiny_detail,
        "gui": _tiny_gui, "gaussians": _tiny_gaussians, "gaussian-render": _tiny_gaussian_render,
        "gaussian-editor": _tiny_gaussian_editor, "gpu-sort": _tiny_gpu_sort, "curves": _tiny_curves}


#: benchmarks that take an image size and a draw path (``--size``, ``--path``)
SIZED = ("gaussian-render",)


def run_bench(what: str, *, quick: bool = False, progress=None, counts=None,
              large: bool = False, size=None, path=None, models=(), tiny: bool = False) -> Iterator[dict]:
    """Yield the result dicts of benchmark ``what`` (a key of BENCHES, or "all");
    ``counts``: splat/point counts for ``estimate``, ``render``, ``editor``, ``closure`` and
    support splats for ``basis`` and ``solve`` (its grab cases)
    (default: each benchmark's own); ``large`` adds the 10M-splat cases of ``io``;
    ``size`` (width, height) applies to ``render`` and :data:`SIZED`, ``path`` ("raster" /
    "compute") to :data:`SIZED`, ``models`` (extra model files, e.g. a real scan) to ``render``;
    ``tiny``: each case's smallest form (:data:`TINY`, for the tests)."""
    names = list(BENCHES) if what == "all" else [what]
    for name in names:
        if tiny:
            yield from TINY[name]()
        elif name == "io":
            yield from _io(quick, progress, counts, large=large)
        elif name == "render":
            yield from _render(quick, progress, counts, size=size, models=models)
        elif name in SIZED:
            yield from BENCHES[name](quick, progress, counts, size=size, path=path)
        else:
            yield from BENCHES[name](quick, progress, counts)

"""Command line: ``splatedit [demo|edit|info|convert|deform|render|bench] ...``.

Bad input (files, edit scripts, parameters) prints one line ``splatedit: error: ...``
to stderr and exits with code 2, without a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import sys
import threading
import time
import warnings
from pathlib import Path

# numpy asks for transparent huge pages on large arrays; where the kernel
# then compacts memory on the first touch (THP defrag "madvise", as here)
# filling 720 MB of new arrays took 2.6-3.5 s instead of 0.8-1.1 s, most of a
# 10M-splat read.  Set before numpy is imported (the user's setting wins)
os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")

from splatedit.app.options import join_negative_values, parse_size, positive_float
from splatedit.bench.runner import BENCHES
from splatedit.errors import InputWarning, ParameterError, SplatEditError

#: the `splatedit bench` cases (one JSON line per case each)
BENCH_NAMES = tuple(BENCHES)

EXIT_BAD_INPUT = 2
#: options taking x,y,z: a value with a leading minus works (``--eye -0.4,1,2``)
VECTOR_OPTIONS = ("--eye", "--target", "--up")
#: 128 + SIGPIPE, what a shell reports for a program killed by a closed pipe
EXIT_BROKEN_PIPE = 141


# ------------------------------------------------------------------ progress
class _Progress:
    """A ``progress(stage, fraction)`` callback drawing one tqdm bar per stage on stderr."""

    def __init__(self, enabled: bool = True):
        self.enabled = enabled
        self._bar = None
        self._stage = None

    def __call__(self, stage: str, fraction: float) -> None:
        if not self.enabled:
            return
        from tqdm import tqdm
        if stage != self._stage:
            self.close()
            self._stage = stage
            self._bar = tqdm(total=1000, desc=stage, leave=False, file=sys.stderr,
                             bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}", disable=None)
        self._bar.n = int(round(fraction * 1000))
        self._bar.refresh()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
            self._stage = None


def _parse_vec3(text: str, name: str) -> tuple[float, float, float]:
    try:
        parts = [float(x) for x in text.split(",")]
    except ValueError:
        parts = []
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(f"{name} must be three comma-separated numbers like 0,0,1, got {text!r}")
    return tuple(parts)  # type: ignore[return-value]


def _positive_count(text: str) -> int:
    try:
        value = int(text.replace("_", ""))
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive whole number, got {text!r}")
    return value


# ------------------------------------------------------------------ commands
def _sig(x, digits: int = 7) -> float | None:
    """``x`` rounded to ``digits`` significant digits (not decimals: a model
    in units of 1e-20 keeps its figures); None for NaN or infinity, which
    JSON cannot hold."""
    x = float(x)
    return float(f"{x:.{digits}g}") if math.isfinite(x) else None


def _print_info(info: dict, as_json: bool) -> None:
    if as_json:
        print(json.dumps(info, allow_nan=False))     # strict JSON: no Infinity / NaN
    else:
        width = max(map(len, info))
        for k, v in info.items():
            print(f"{k:<{width}}  {v}")


def _gaussian_info(args) -> dict:
    """``info`` of a Gaussian splatting PLY: kind, count, SH degree, opacity and
    scale percentiles, anisotropy, bounding box, kept extra properties."""
    import numpy as np
    from splatedit.io import read_gaussians
    g = read_gaussians(args.file, progress=args.progress)
    lo, hi = g.bounds()
    pct = (5, 50, 95)
    s = np.exp(g.log_scales.astype(np.float64))
    srt = np.sort(s, axis=1)
    return {
        "file": str(args.file),
        "kind": g.kind.value,
        "gaussians": len(g),
        "sh_degree": g.sh_degree,
        "normals": g.normals is not None,
        "extra_properties": list(g.extra),
        "bounds_min": [_sig(x) for x in lo],
        "bounds_max": [_sig(x) for x in hi],
        "diagonal": _sig(np.linalg.norm(hi - lo)),
        "opacity_p5_p50_p95": [_sig(x, 4) for x in np.percentile(g.opacities(), pct)],
        "opacity_below_0.5": int((g.opacity_logits < 0).sum()),
        "scale_max_p5_p50_p95": [_sig(x, 4) for x in np.percentile(srt[:, -1], pct)],
        "scale_min_p5_p50_p95": [_sig(x, 4) for x in np.percentile(srt[:, 0], pct)],
        "anisotropy_p5_p50_p95": [_sig(x, 4) for x in np.percentile(srt[:, -1] / srt[:, -2], pct)],
    }


def cmd_info(args) -> int:
    """Counts, bounds and cleanliness figures.  Up to INFO_EXACT_MAX_POINTS
    splats everything is exact; above, spacing, boundary splats and outliers
    are estimated from spatial patches (listed under ``estimated``) and
    stray clusters (a global graph property) are not computed (null)."""
    import numpy as np
    from splatedit.io import is_gaussian_file, read
    if is_gaussian_file(args.file):
        _print_info(_gaussian_info(args), args.json)
        return 0
    from splatedit.model.quality import assess, estimate_quality, scan_fields_present
    from splatedit.model.spacing import point_spacing
    from splatedit.tolerances import INFO_EXACT_MAX_POINTS
    cloud = read(args.file, progress=args.progress)
    lo, hi = cloud.bounds()
    radii = cloud.radii
    est = estimate_quality(cloud, lower=lo) if cloud.n > INFO_EXACT_MAX_POINTS else None
    info = {
        "file": str(args.file),
        "splats": cloud.n,
        "faces": 0 if cloud.faces is None else int(len(cloud.faces)),
        "colors": cloud.colors is not None,
        **scan_fields_present(cloud),
        "origin": [_sig(x, 15) for x in cloud.origin],
        "bounds_min": [_sig(x) for x in lo],
        "bounds_max": [_sig(x) for x in hi],
        "diagonal": _sig(np.linalg.norm(hi - lo)),
    }
    extent, note = _info_extent(cloud)
    info.update(extent)
    med = np.median(radii)
    if est is None:
        quality = assess(cloud)
        info.update({
            "spacing": _sig(point_spacing(cloud.positions)),
            "splat_radius_median": _sig(med),
            "splat_radius_max": _sig(radii.max()),
            "splat_radius_max_rel_median": _sig(quality.radius_max_rel_median, 4),
            "boundary_splats": quality.boundary_count,
            "outliers": quality.outliers.count,
            "outliers_statistical": int(quality.outliers.statistical.sum()),
            "outliers_isolated": int(quality.outliers.isolated.sum()),
            "stray_cluster_points": int(quality.stray_clusters.sum()),
        })
    else:
        info.update({
            "spacing": _sig(est.spacing),
            "splat_radius_median": _sig(med),
            "splat_radius_max": _sig(radii.max()),
            "splat_radius_max_rel_median": _sig(radii.max() / med, 4),
            "boundary_splats": est.boundary,
            "outliers": est.outliers,
            "outliers_statistical": est.statistical,
            "outliers_isolated": est.isolated,
            "stray_cluster_points": None,
            "estimated": ["spacing", "outliers", "outliers_statistical", "outliers_isolated"]
                         + ([] if cloud.faces is not None else ["boundary_splats"]),
            "sample_points": est.sample_points,
        })
    _print_info(info | note, args.json)
    return 0


def _info_extent(cloud) -> tuple[dict, dict]:
    """``info``'s scanner dimensions held but all zero and the main body's
    extent (:func:`splatedit.model.extent.framing_extent`); and a ``note``
    about the points far outside it, printed last."""
    from splatedit.model.extent import framing_extent
    from splatedit.model.quality import scan_fields_all_zero
    zero = scan_fields_all_zero(cloud)
    ext = framing_extent(cloud.positions)
    return (({"all_zero": zero} if zero else {})
            | {"main_body_diagonal": _sig(2 * ext.radius), "far_from_main_body": ext.n_far},
            {"note": ext.note()} if ext.note() else {})


def cmd_convert(args) -> int:
    from splatedit.io import check_output_path, is_gaussian_file, read, write
    check_output_path(args.output, overwrite=args.force, protect=args.input)
    if is_gaussian_file(args.input) and not args.to_splats and Path(args.output).suffix.lower() == ".ply":
        from splatedit.io import read_gaussians, write_gaussians
        if args.remove_outliers:
            raise ParameterError("--remove-outliers", "works on point clouds, not on Gaussian scenes")
        g = read_gaussians(args.input, progress=args.progress)
        write_gaussians(args.output, g, overwrite=args.force)
        print(f"wrote {args.output}: {len(g)} Gaussians ({g.kind.value}, SH degree {g.sh_degree})")
        return 0
    cloud = read(args.input, progress=args.progress)
    if args.remove_outliers:
        cloud = _remove_outliers(args, cloud)
    write(args.output, cloud, overwrite=args.force)
    print(f"wrote {args.output}: {cloud.n} splats" + ("" if cloud.faces is None else f", {len(cloud.faces)} faces"))
    return 0


def _print_edit(args, rep) -> None:
    """One edit's report line, its distortion figures and (stderr) warnings:
    conflicting constraints, splats stretched beyond DISTORTION_WARN_STRETCH."""
    args.progress.close()
    print(rep.line())
    if rep.distortion is not None:
        print(rep.distortion_line())
    warnings = list(rep.warnings)
    if rep.distortion_warning():
        warnings.append(rep.distortion_warning())
    for w in warnings:
        print(f"splatedit: warning: {w}", file=sys.stderr, flush=True)


def _remove_outliers(args, cloud):
    """``convert --remove-outliers``: drop statistical and isolated outliers
    of a point cloud (a mesh is refused: its faces would need re-indexing and
    a vertex used by faces is part of the surface)."""
    from splatedit.model.outliers import detect_outliers, stray_clusters
    if cloud.faces is not None:
        raise ParameterError("--remove-outliers", f"{args.input} is a triangle mesh "
                             f"({len(cloud.faces)} faces); outlier removal works on point clouds only")
    flags = detect_outliers(cloud.positions)
    strays = stray_clusters(cloud.positions, flags.isolation_radius) & ~flags.mask
    drop = flags.mask | strays
    args.progress.close()
    print(f"removed {int(drop.sum())} outlier(s) of {cloud.n} points "
          f"({int(flags.statistical.sum())} statistical, {int(flags.isolated.sum())} isolated, "
          f"{int(strays.sum())} in small far clusters)")
    return cloud.subset(~drop) if drop.any() else cloud


def _run_edits(args, cloud, script_path):
    from splatedit.script import load_script, run_script
    script = load_script(script_path)
    return run_script(cloud, script, method=getattr(args, "method", None), tol=getattr(args, "tol", None),
                      source=str(script_path), progress=args.progress,
                      on_edit=lambda rep: _print_edit(args, rep))


def cmd_deform(args) -> int:
    from splatedit.io import check_output_path, check_readable_file, is_gaussian_file, read, write
    check_output_path(args.output, overwrite=args.force, protect=args.input)
    check_readable_file(args.edit)
    if is_gaussian_file(args.input):
        return _deform_gaussians(args)
    cloud = read(args.input, progress=args.progress)
    t0 = time.perf_counter()
    out, reports = _run_edits(args, cloud, args.edit)
    write(args.output, out, overwrite=args.force)
    print(f"wrote {args.output}: {out.n} splats, {len(reports)} edit(s) in {time.perf_counter() - t0:.2f} s")
    return 0


def _deform_gaussians(args) -> int:
    """``deform`` of a Gaussian scene: edits select centres; covariances and
    spherical harmonics follow the Jacobian; the output is a Gaussian PLY."""
    from splatedit.gaussian_script import run_script_gaussians
    from splatedit.io import read_gaussians, write_gaussians
    from splatedit.script import load_script
    if Path(args.output).suffix.lower() != ".ply":
        raise ParameterError("--output", f"{args.input} is a Gaussian scene: the output must be a .ply")
    script = load_script(args.edit)
    g = read_gaussians(args.input, progress=args.progress)
    t0 = time.perf_counter()
    out, reports = run_script_gaussians(g, script, method=args.method, tol=args.tol,
                                        source=str(args.edit), progress=args.progress,
                                        on_edit=lambda rep: _print_edit(args, rep))
    write_gaussians(args.output, out, overwrite=args.force)
    print(f"wrote {args.output}: {len(out)} Gaussians, {len(reports)} edit(s) in "
          f"{time.perf_counter() - t0:.2f} s")
    return 0


def _camera_from_args(args, cloud):
    """The camera of ``splatedit render``: the editor's first view (the main
    body framed from the front about the up axis: :func:`splatedit.render.framing.
    default_view`), then the flags override; the view's note about far points
    goes to stderr when it frames the default extent."""
    from splatedit.render.camera import Camera
    from splatedit.render.framing import default_view, screen_up
    if args.fov is not None and not 0.0 < args.fov < 179.0:
        raise ParameterError("--fov", f"must be in (0, 179) degrees, got {args.fov:g}")
    try:
        view = default_view(cloud, args.size, path=args.input, up=args.up, fov_deg=args.fov)
        if args.eye is None and args.target is None:
            camera = view.camera
        else:
            eye = view.camera.eye if args.eye is None else args.eye
            target = view.camera.target if args.target is None else args.target
            # the model's up, unless --eye looks along it (straight down on a Z-up scan)
            up = args.up if args.up is not None else screen_up(view.camera.up, eye, target)
            camera = Camera(eye, target, up=up, fov_deg=view.camera.fov_deg)
    except ParameterError as exc:
        raise ParameterError(f"--{exc.name}", str(exc).split(": ", 1)[1]) from None
    if args.target is None and view.extent.note():
        args.progress.close()
        print(f"splatedit: note: {view.extent.note()}; the view frames the main body", file=sys.stderr)
    return camera


def cmd_render(args) -> int:
    from splatedit.io.atomic import check_writable_target
    from splatedit.render.headless import check_render_memory, render_to_png
    if args.buffers is not None and Path(args.buffers).resolve() == Path(args.output).resolve():
        raise ParameterError("--buffers", "must differ from the PNG path (-o)")
    check_render_memory(args.size, args.buffers is not None)    # before reading anything
    for target in (args.output, args.buffers):
        if target is not None:
            check_writable_target(target, overwrite=args.force, protect=args.input)
    cloud = _read_model(args.input, args.progress)
    from splatedit.model.gaussians import GaussianCloud
    if isinstance(cloud, GaussianCloud):
        return _render_gaussians(args, cloud)
    camera = _camera_from_args(args, cloud)
    basis_rows = d_c = None
    if args.edit is not None:
        cloud, basis_rows, d_c = _gpu_edit(args, cloud)
    render_to_png(cloud, args.output, size=args.size, camera=camera, basis=basis_rows, dC=d_c,
                  buffers_path=args.buffers)
    print(f"wrote {args.output} ({args.size[0]}x{args.size[1]}, {cloud.n} splats"
          + (", deformed on the GPU" if basis_rows is not None else "") + ")"
          + (f" and {args.buffers}" if args.buffers else ""))
    return 0


def _read_model(path, progress):
    """The model loader of ``splatedit render``: a GaussianCloud for a
    Gaussian Splatting scene (rendered by the Gaussian renderer), else a
    SplatCloud."""
    from splatedit.io import is_gaussian_file, read, read_gaussians
    if is_gaussian_file(path):
        return read_gaussians(path, progress=progress)
    return read(path, progress=progress)


def _render_gaussians(args, cloud) -> int:
    """``splatedit render`` of a GaussianCloud: camera flags as for splats, an
    edit script's single edit fitted on the Gaussians' splat proxy and applied
    on the GPU (centres, covariances, SH frames)."""
    import numpy as np
    from splatedit.render.gs_headless import render_gaussians_to_png
    if args.buffers is not None:
        raise ParameterError("--buffers", "is not available for Gaussian splatting scenes")
    proxy = cloud.proxy_splats()
    camera = _camera_from_args(args, proxy)
    basis_rows = d_c = None
    on_cpu = False
    if args.edit is not None:
        from splatedit.script import load_script
        if len(load_script(args.edit).edits) != 1:
            raise ParameterError("--edit", f"{args.edit}: a Gaussian scene takes one edit per render "
                                           "(chained edits need the Gaussian CPU deformation)")
        def gpu_can_draw(rows, d_c):
            return isinstance(d_c, np.ndarray) and len(rows) == 5

        _, basis_rows, d_c = _gpu_edit(args, proxy, on_gpu=gpu_can_draw)
        if not gpu_can_draw(basis_rows, d_c):
            # the Gaussian GPU pass draws a plain dC only: a turning handle (rotation mode) or the
            # detail mode is applied on the CPU as `splatedit deform` does, then drawn undeformed
            from splatedit.gaussian_script import run_script_gaussians
            cloud, _ = run_script_gaussians(cloud, load_script(args.edit), source=str(args.edit),
                                            progress=args.progress)
            basis_rows = d_c = None
            on_cpu = True
    render_gaussians_to_png(cloud, args.output, size=args.size, camera=camera, basis=basis_rows, dC=d_c)
    how = ", deformed on the CPU" if on_cpu else ", deformed on the GPU" if basis_rows is not None else ""
    print(f"wrote {args.output} ({args.size[0]}x{args.size[1]}, {len(cloud)} Gaussians, SH degree "
          f"{cloud.sh_degree}{how})")
    return 0


def _gpu_edit(args, cloud, on_gpu=None):
    """Apply an edit script for rendering: every edit but the last is committed
    on the CPU (each edit's result is the next one's base); the last edit goes
    to the GPU as basis rows plus its control-frame displacement dC.
    ``on_gpu(rows, dC)``: whether the caller's renderer can draw them (else
    it deforms on the CPU, and the report says so).

    Returns (base cloud of the last edit, (indices, B, Bx, By, Bz), dC).
    """
    import dataclasses
    from splatedit.script import fit_edit, load_script, run_script
    script = load_script(args.edit)
    source = str(args.edit)
    if len(script.edits) > 1:
        head = dataclasses.replace(script, edits=script.edits[:-1])
        cloud, _ = run_script(cloud, head, source=source, progress=args.progress,
                              on_edit=lambda rep: _print_edit(args, rep))
    resolved, basis, d_c = fit_edit(cloud, script.edits[-1], script.solver, source=source,
                                    progress=args.progress)
    args.progress.close()
    st = basis.stats
    mode = script.edits[-1].deformation.value
    detail = getattr(basis, "detail_for_gpu", None)   # the detail mode (splatedit.deform.detail)
    rows = basis.rows_for_gpu() + ((detail(),) if detail else ())
    where = ("uploaded to the GPU" if on_gpu is None or on_gpu(rows, d_c)
             else f"fitted; the {mode} edit is applied on the CPU")
    print(f"edit {len(script.edits) - 1}: {mode} deformation, support {len(basis.indices)} splats, "
          f"{st['method']} with {st['n_centers']} centers (residual {st['residual']:.2e}), "
          f"{basis.n_columns} basis columns {where}")
    for c in basis.constraints.conflicts:
        print(f"splatedit: warning: edit {len(script.edits) - 1}: {c.describe(basis.constraints.spacing)}",
              file=sys.stderr)
    from splatedit.deform.distortion import basis_distortion
    dist = basis.distortion(cloud, d_c) if detail else basis_distortion(basis, cloud, d_c)
    print(f"  distortion: {dist.summary()}")
    if dist.exceeds_warn:
        print(f"splatedit: warning: edit {len(script.edits) - 1} stretches {dist.n_above_warn} of {dist.n} "
              f"support splats more than {dist.warn:g}x (max {dist.max_stretch:.2f}x)", file=sys.stderr)
    return cloud, rows, d_c


def cmd_demo(args) -> int:
    from splatedit.demo import run_demo
    run_demo(Path(args.output_dir), progress=args.progress, log=print, render=not args.no_render,
             overwrite=args.force)
    return 0


def cmd_edit(args) -> int:
    from splatedit.app.editor import run_editor
    from splatedit.app.options import options_from_args
    return run_editor(args.file, **options_from_args(args))


def cmd_main(args) -> int:
    """No sub-command: the editor when a display is present, else the headless demo."""
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        from splatedit.app.editor import run_editor
        return run_editor(None)
    args.output_dir = str(_fresh_directory(Path("splatedit-demo")))
    args.no_render = False
    args.force = False
    return cmd_demo(args)


def _fresh_directory(base: Path) -> Path:
    """``base`` if it does not exist yet, else ``base-2``, ``base-3``, ... (never
    writes into a folder that holds earlier results)."""
    candidate, k = base, 1
    while candidate.exists():
        k += 1
        candidate = base.with_name(f"{base.name}-{k}")
    return candidate


def cmd_bench(args) -> int:
    from splatedit.bench.runner import run_bench
    what = args.what
    if args.gaussians:
        if what != "render":
            raise ParameterError("--gaussians", f"applies to 'bench render', not 'bench {what}'")
        what = "gaussian-render"
    for line in run_bench(what, quick=args.quick, progress=args.progress, counts=args.splats, large=args.large):
        print(json.dumps(line), flush=True)
    return 0


# ------------------------------------------------------------------- parser
class _Parser(argparse.ArgumentParser):
    """argparse with the one-line error contract: ``splatedit: error: render:
    argument --size: ...`` on stderr and exit code 2, no usage block (``-h``
    still prints the usage).  Sub-command parsers inherit the class."""

    def error(self, message: str):
        sub = self.prog.split(" ", 1)[1] if " " in self.prog else ""
        where = f"{sub}: " if sub else ""
        hint = f" (see 'splatedit {sub + ' ' if sub else ''}-h')"
        self.exit(EXIT_BAD_INPUT, f"splatedit: error: {where}{message}{hint}\n")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="splatedit", description=__doc__.split("\n")[0])
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bars")
    sub = p.add_subparsers(dest="command")

    s = sub.add_parser("demo", help="headless demo edit of the bundled bunny (writes PLY, JSON and PNG)")
    s.add_argument("-o", "--output-dir", default=".", help="where to write the results (default: .)")
    s.add_argument("--no-render", action="store_true", help="skip the PNG renders")
    s.add_argument("-f", "--force", action="store_true", help="overwrite existing outputs")
    s.set_defaults(func=cmd_demo)

    s = sub.add_parser("info", help="counts, bounds, attributes, spacing, splat sizes, boundary splats and outliers of a model")
    s.add_argument("file")
    s.add_argument("--json", action="store_true", help="print one JSON object")
    s.set_defaults(func=cmd_info)

    s = sub.add_parser("convert", help="convert between PLY, XYZ, OFF, LAS/LAZ, E57, PCD and PTS by extension "
                                       "(estimates normals and sizes when missing); a Gaussian splatting PLY "
                                       "stays one (see --to-splats)")
    s.add_argument("input")
    s.add_argument("output")
    s.add_argument("--to-splats", action="store_true",
                   help="Gaussian input: write plain splats (lossy: a disc per Gaussian from its two "
                        "largest axes at 2 sigma, colour from the DC term)")
    s.add_argument("--remove-outliers", action="store_true",
                   help="drop statistical and isolated outlier points (point clouds only)")
    s.add_argument("-f", "--force", action="store_true", help="overwrite OUTPUT if it exists")
    s.set_defaults(func=cmd_convert)

    s = sub.add_parser("deform", help="apply a JSON edit script to a model")
    s.add_argument("input")
    s.add_argument("--edit", required=True, type=Path, help="edit script (JSON)")
    s.add_argument("-o", "--output", required=True, help="output PLY")
    s.add_argument("--method", choices=("auto", "lu", "iqr"), help="override the script's solver method")
    s.add_argument("--tol", type=positive_float, help="override the script's IQR tolerance")
    s.add_argument("-f", "--force", action="store_true", help="overwrite OUTPUT if it exists (even the input)")
    s.set_defaults(func=cmd_deform)

    s = sub.add_parser("render", help="render a model to PNG with the Vulkan EWA splat renderer")
    s.add_argument("input")
    s.add_argument("-o", "--output", required=True, help="output PNG")
    s.add_argument("--size", type=parse_size, default=(1280, 720), help="WxH (default 1280x720)")
    s.add_argument("--eye", type=lambda t: _parse_vec3(t, "--eye"), metavar="X,Y,Z",
                   help="camera position (default: the editor's first view, see README)")
    s.add_argument("--target", type=lambda t: _parse_vec3(t, "--target"), metavar="X,Y,Z",
                   help="look-at point (default: the centre of the model's main body)")
    s.add_argument("--up", type=lambda t: _parse_vec3(t, "--up"), metavar="X,Y,Z",
                   help="up direction (default: the model's detected up axis, as in the editor)")
    s.add_argument("--fov", type=float, default=None, help="vertical field of view in degrees")
    s.add_argument("--edit", type=Path, help="apply this edit script on the GPU before rendering")
    s.add_argument("--buffers", help="also save depth/normal/weight/color float arrays to this .npz")
    s.add_argument("-f", "--force", action="store_true", help="overwrite outputs")
    s.set_defaults(func=cmd_render)

    from splatedit.app.options import CONTROLS, add_arguments
    s = sub.add_parser("edit", help="interactive editor (a window; F1 in it lists the controls)",
                       epilog=CONTROLS, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(s)
    s.set_defaults(func=cmd_edit)

    s = sub.add_parser("bench", help="benchmarks; print one JSON line per case")
    s.add_argument("what", choices=(*BENCH_NAMES, "all"))
    s.add_argument("--quick", action="store_true", help="small sizes only (a smoke run)")
    s.add_argument("--gaussians", action="store_true",
                   help="with 'render': the Gaussian splatting renderer (100k and 1M Gaussians, both sorts)")
    s.add_argument("--splats", type=_positive_count, nargs="+", metavar="N",
                   help="point/splat counts of estimate, render, editor and the Gaussian benches "
                        "(e.g. --splats 1000000 10000000)")
    s.add_argument("--large", action="store_true",
                   help="io: also the 10M-splat PLY read (writes an 840 MB file to the temp folder)")
    s.set_defaults(func=cmd_bench)
    return p


def _route_warnings(progress: _Progress) -> None:
    """Inside ``warnings.catch_warnings()``: an :class:`InputWarning` (input
    partly ignored) is printed as one line ``splatedit: warning: ...``; numpy's
    RuntimeWarnings (overflow in a cast, ...) are not for the user, whose
    problems get their own message."""
    def show(message, category, filename, lineno, file=None, line=None):
        progress.close()
        print(f"splatedit: warning: {message}", file=sys.stderr, flush=True)

    warnings.simplefilter("ignore", RuntimeWarning)
    warnings.simplefilter("always", InputWarning)
    warnings.showwarning = show


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(join_negative_values(sys.argv[1:] if argv is None else list(argv), VECTOR_OPTIONS))
    args.progress = _Progress(enabled=not args.quiet)
    func = getattr(args, "func", cmd_main)
    restore = _sigterm_as_interrupt()
    try:
        with warnings.catch_warnings():
            _route_warnings(args.progress)
            code = func(args) or 0
        sys.stdout.flush()      # a closed pipe fails here, not in Python's exit flush
        return code
    except SplatEditError as exc:
        args.progress.close()
        print(f"splatedit: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        args.progress.close()
        print("splatedit: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of stdout went away (``splatedit info x.ply | head -1``):
        # stop quietly, and keep Python's exit flush from failing again
        with contextlib.suppress(OSError, ValueError, AttributeError):
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        return EXIT_BROKEN_PIPE
    finally:
        args.progress.close()
        restore()


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt


def _sigterm_as_interrupt():
    """Handle SIGTERM like Ctrl+C (KeyboardInterrupt: temporary files are
    removed, the target is untouched, exit code 130).  Returns a function
    that puts the previous handler back (a no-op outside the main thread,
    where signal handlers cannot be set)."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    previous = signal.signal(signal.SIGTERM, _raise_interrupt)
    return lambda: signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)


if __name__ == "__main__":
    sys.exit(main())

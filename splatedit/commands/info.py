"""``splatedit info``: counts, bounds, attributes, spacing, splat sizes,
boundary splats and outliers of a model (or the figures of a Gaussian
splatting scene), as aligned text or one JSON object."""

from __future__ import annotations

import importlib
import json
import math
import threading


def _sig(x, digits: int = 7) -> float | None:
    """``x`` rounded to ``digits`` significant digits (not decimals: a model
    in units of 1e-20 keeps its figures); None for NaN or infinity, which
    JSON cannot hold."""
    x = float(x)
    return float(f"{x:.{digits}g}") if math.isfinite(x) else None


def _import_in_background(module: str) -> threading.Thread:
    """Start importing ``module`` on a thread and return it (join it before
    using the module).  The figures need scipy (0.5-1 s of imports: Python
    work holding the GIL); reading a binary PLY is file I/O and numpy loops
    that release it, so on two cores the import and the read overlap.  A
    failed import is raised again by the caller's own import."""
    def load():
        try:
            importlib.import_module(module)
        except BaseException:       # the caller's import reports it
            pass

    thread = threading.Thread(target=load, name=f"import {module}", daemon=True)
    thread.start()
    return thread


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


def _copc_info(args) -> dict:
    """``info`` of a COPC file from its header and hierarchy alone (no point
    is decompressed, whatever the file's size): counts, bounds, the octree's
    cube, levels, nodes and points per level, root spacing, and the local
    origin edit scripts' coordinates are relative to."""
    import os
    from splatedit.io.copc import CopcFile, file_origin
    with CopcFile.open(args.file) as f:
        per_level = [0] * (f.max_depth + 1)
        nodes_level = [0] * (f.max_depth + 1)
        for k, n in f.nodes.items():
            per_level[k.depth] += n.point_count
            nodes_level[k.depth] += 1
        lo, hi = f.point_bounds
        return {
            "file": str(args.file),
            "kind": "COPC",
            "points": f.point_count,
            "point_format": f.point_format,
            "colors": f.has_colour,
            "intensity": f.has_intensity,
            "bounds_min": [_sig(x, 10) for x in lo],
            "bounds_max": [_sig(x, 10) for x in hi],
            "diagonal": _sig(float(((hi - lo) ** 2).sum()) ** 0.5),
            "scale": [_sig(x) for x in f.scale],
            "offset": [_sig(x, 15) for x in f.offset],
            # the local origin of the editor and of edit scripts (coordinates = file - origin),
            # as for the file read whole
            "origin": [_sig(x, 15) for x in file_origin(f)],
            "octree_center": [_sig(x, 10) for x in f.center],
            "octree_halfsize": _sig(f.halfsize),
            "root_spacing": _sig(f.spacing),
            "levels": f.max_depth + 1,
            "nodes": len(f.nodes),
            "nodes_per_level": nodes_level,
            "points_per_level": per_level,
            "largest_node": max((n.point_count for n in f.nodes.values()), default=0),
            "file_bytes": os.path.getsize(args.file),
            "read": "header and hierarchy only (no point data)",
        }


def cmd_info(args) -> int:
    """Counts, bounds and cleanliness figures.  Up to INFO_EXACT_MAX_POINTS
    splats everything is exact; above, spacing, boundary splats and outliers
    are estimated from spatial patches (listed under ``estimated``) and
    stray clusters (a global graph property) are not computed (null).  A
    large binary PLY with splat axes is read keeping only the centres and
    radii (:func:`splatedit.io.read_summary`)."""
    import numpy as np
    from splatedit.io import is_gaussian_file, read, read_summary
    if is_gaussian_file(args.file):
        _print_info(_gaussian_info(args), args.json)
        return 0
    from splatedit.commands.outofcore import is_copc_path
    if is_copc_path(args.file):
        _print_info(_copc_info(args), args.json)
        return 0
    # the read's own modules first: the thread below then imports none of them
    importlib.import_module("splatedit.io._plysummary")
    from splatedit.model.summary import CloudSummary
    from splatedit.tolerances import INFO_EXACT_MAX_POINTS
    loading = _import_in_background("splatedit.model.quality")
    model = read_summary(args.file, progress=args.progress, lean_above=INFO_EXACT_MAX_POINTS)
    loading.join()
    from splatedit.model.quality import estimate_quality
    lo, hi = model.bounds()
    est = estimate_quality(model, lower=lo) if model.n > INFO_EXACT_MAX_POINTS else None
    if est is None and model.cloud is None:     # no usable patches: every figure exactly
        model = CloudSummary.of_cloud(read(args.file, progress=args.progress))
    radii = model.radii
    rmax = float(radii.max())
    # the radii are a fresh array (read or computed for this call): partitioned in place
    med = float(np.median(radii, overwrite_input=True))
    info = {
        "file": str(args.file),
        "splats": model.n,
        "faces": 0 if model.faces is None else int(len(model.faces)),
        "colors": model.colors,
        "intensity": model.intensity,
        "classification": model.classification,
        "origin": [_sig(x, 15) for x in model.origin],
        "bounds_min": [_sig(x) for x in lo],
        "bounds_max": [_sig(x) for x in hi],
        "diagonal": _sig(np.linalg.norm(hi - lo)),
    }
    extent, note = _info_extent(model)
    info.update(extent)
    if est is None:
        info.update(_exact_figures(model.cloud, med, rmax))
    else:
        info.update({
            "spacing": _sig(est.spacing),
            "splat_radius_median": _sig(med),
            "splat_radius_max": _sig(rmax),
            "splat_radius_max_rel_median": _sig(rmax / med, 4),
            "boundary_splats": est.boundary,
            "outliers": est.outliers,
            "outliers_statistical": est.statistical,
            "outliers_isolated": est.isolated,
            "stray_cluster_points": None,
            "estimated": ["spacing", "outliers", "outliers_statistical", "outliers_isolated"]
                         + ([] if model.faces is not None else ["boundary_splats"]),
            "sample_points": est.sample_points,
        })
    _print_info(info | note, args.json)
    return 0


def _info_extent(model) -> tuple[dict, dict]:
    """``info``'s scanner dimensions held but all zero (when the whole cloud
    was read) and the main body's extent (:func:`splatedit.model.extent.
    framing_extent`); and a ``note`` about the points far outside it, printed last."""
    from splatedit.model.extent import framing_extent
    from splatedit.model.summary import scan_fields_all_zero
    zero = scan_fields_all_zero(model.cloud) if model.cloud is not None else []
    ext = framing_extent(model.positions)
    return (({"all_zero": zero} if zero else {})
            | {"main_body_diagonal": _sig(2 * ext.radius), "far_from_main_body": ext.n_far},
            {"note": ext.note()} if ext.note() else {})


def _exact_figures(cloud, med: float, rmax: float) -> dict:
    """Spacing, splat-size and cleanliness figures of a whole cloud, exactly."""
    from splatedit.model.quality import assess
    quality = assess(cloud)
    return {
        "spacing": _sig(quality.spacing),
        "splat_radius_median": _sig(med),
        "splat_radius_max": _sig(rmax),
        "splat_radius_max_rel_median": _sig(quality.radius_max_rel_median, 4),
        "boundary_splats": quality.boundary_count,
        "outliers": quality.outliers.count,
        "outliers_statistical": int(quality.outliers.statistical.sum()),
        "outliers_isolated": int(quality.outliers.isolated.sum()),
        "stray_cluster_points": int(quality.stray_clusters.sum()),
    }

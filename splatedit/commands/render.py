"""``splatedit render``: a model to PNG with the Vulkan splat renderer (or
the Gaussian renderer for a Gaussian scene), framed automatically or by the
camera flags, optionally deformed on the GPU by an edit script."""

from __future__ import annotations

import sys
from pathlib import Path

from splatedit.commands.edits import _print_edit
from splatedit.errors import ParameterError


def _camera_from_args(args, cloud):
    """The camera of ``splatedit render``: framing the model, then the flags override."""
    import numpy as np
    from splatedit.render.camera import Camera
    w, h = args.size
    lo, hi = cloud.bounds()
    # frames a single point by its splat (the largest semi-axis; einsum: no (n,) norms)
    rmax = float(np.sqrt(max(np.einsum("ij,ij->i", cloud.u, cloud.u).max(),
                             np.einsum("ij,ij->i", cloud.v, cloud.v).max())))
    # all centres in one point: look at the splat face-on (from +z it may be edge-on)
    direction = cloud.normals[0] if not np.any(hi > lo) else (0.0, 0.0, 1.0)
    base = Camera.frame(lo, hi, aspect=w / h, min_radius=rmax, direction=direction)
    if args.fov is not None and not 0.0 < args.fov < 179.0:
        raise ParameterError("--fov", f"must be in (0, 179) degrees, got {args.fov:g}")
    fov = base.fov_deg if args.fov is None else args.fov
    if args.eye is None and args.target is None and args.up is None and args.fov is None:
        return base
    if args.eye is None and args.fov is not None and args.target is None and args.up is None:
        return Camera.frame(lo, hi, aspect=w / h, fov_deg=fov, min_radius=rmax, direction=direction)
    target = base.target if args.target is None else args.target
    eye = base.eye if args.eye is None else args.eye
    up = base.up if args.up is None else args.up
    try:
        return Camera(eye, target, up=up, fov_deg=fov)
    except ParameterError as exc:
        raise ParameterError(f"--{exc.name}", str(exc).split(": ", 1)[1]) from None


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
        _, basis_rows, d_c = _gpu_edit(args, proxy)
        if not isinstance(d_c, np.ndarray) or len(basis_rows) != 5:
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


def _gpu_edit(args, cloud):
    """Apply an edit script for rendering: every edit but the last is committed
    on the CPU (each edit's result is the next one's base); the last edit goes
    to the GPU as basis rows plus its control-frame displacement dC.

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
    print(f"edit {len(script.edits) - 1}: {mode} deformation, support {len(basis.indices)} splats, "
          f"{st['method']} with {st['n_centers']} centers (residual {st['residual']:.2e}), "
          f"{basis.n_columns} basis columns uploaded to the GPU")
    for c in basis.constraints.conflicts:
        print(f"splatedit: warning: edit {len(script.edits) - 1}: {c.describe(basis.constraints.spacing)}",
              file=sys.stderr)
    from splatedit.deform.distortion import basis_distortion
    detail = getattr(basis, "detail_for_gpu", None)   # the detail mode (splatedit.deform.detail)
    dist = basis.distortion(cloud, d_c) if detail else basis_distortion(basis, cloud, d_c)
    print(f"  distortion: {dist.summary()}")
    if dist.exceeds_warn:
        print(f"splatedit: warning: edit {len(script.edits) - 1} stretches {dist.n_above_warn} of {dist.n} "
              f"support splats more than {dist.warn:g}x (max {dist.max_stretch:.2f}x)", file=sys.stderr)
    return cloud, basis.rows_for_gpu() + ((detail(),) if detail else ()), d_c

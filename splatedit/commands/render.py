"""``splatedit render``: a model to PNG with the Vulkan splat renderer (or
the Gaussian renderer for a Gaussian scene), framed automatically or by the
camera flags, optionally deformed on the GPU by an edit script."""

from __future__ import annotations

import sys
from pathlib import Path

from splatedit.commands.edits import print_edit
from splatedit.errors import ParameterError


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
        reason = str(exc).split(": ", 1)[1]
        if getattr(args, exc.name, None) is not None:        # the user's own flag
            raise ParameterError(f"--{exc.name}", reason) from None
        # a default the command chose (no such flag given): name the model, not a flag
        from splatedit.errors import InputError
        raise InputError(f"cannot frame a default view (its {exc.name} would be {reason}); "
                         f"give --eye and --target", path=str(args.input)) from None
    _clip_to_main_body(camera, view.extent)
    if args.target is None and view.extent.note():
        args.progress.close()
        print(f"splatedit: note: {view.extent.note()}; the view frames the main body", file=sys.stderr)
    return camera


def _clip_to_main_body(camera, extent) -> None:
    """Near/far for a model with far outliers: chosen from the whole box, the
    near plane (at least ``RENDER_NEAR_FAR_RATIO`` of the far one, for depth
    precision) lay beyond the main body when one point sat 1e9 away, and the
    image came out blank with exit 0.  Then the main body's depth range is
    used, the far plane pushed out as far as that ratio allows: outliers
    beyond it are clipped, the body is drawn."""
    from splatedit.tolerances import RENDER_NEAR_FAR_RATIO
    if not extent.robust:
        return
    body_near, body_far = camera.clip_range(extent.lo, extent.hi)
    full_near, full_far = camera.clip_range(extent.full_lo, extent.full_hi)
    if full_near > body_near:
        camera.near = body_near
        camera.far = max(body_far, min(full_far, body_near / RENDER_NEAR_FAR_RATIO))


def cmd_render(args) -> int:
    """Run ``splatedit render``: draw a model (optionally after an edit script) headless into a PNG;
    returns the exit status."""
    from splatedit.io import check_output_path
    from splatedit.render.splat.headless import check_render_memory, render_to_png
    if args.buffers is not None and Path(args.buffers).resolve() == Path(args.output).resolve():
        raise ParameterError("--buffers", "must differ from the PNG path (-o)")
    check_render_memory(args.size, args.buffers is not None)    # before reading anything
    # what is written must be what the name says: a PNG, and numpy's .npz
    # (`render m.ply -o m.ply --force` wrote a PNG over the model)
    for target, ext in ((args.output, ".png"), (args.buffers, ".npz")):
        if target is not None:
            check_output_path(target, overwrite=args.force, protect=args.input, extensions=(ext,))
    from splatedit.io import is_gaussian_file
    if getattr(args, "edl", False) and is_gaussian_file(args.input):
        raise ParameterError("--edl", f"eye-dome lighting is for point-splat models; {args.input} is a Gaussian splat scene")
    from splatedit.commands.outofcore import is_copc_path, render_copc
    if is_copc_path(args.input):
        return render_copc(args, _camera_from_args)
    if args.edit is not None and not is_gaussian_file(args.input):
        check_gpu_columns(args.edit)        # before the read and the fit (seconds, gigabytes)
    cloud = _read_model(args.input, args.progress)
    from splatedit.model.gaussians import GaussianCloud
    if isinstance(cloud, GaussianCloud):
        return _render_gaussians(args, cloud)
    camera = _camera_from_args(args, cloud)
    basis_rows = d_c = None
    if args.edit is not None:
        cloud, basis_rows, d_c = _gpu_edit(args, cloud, on_gpu=_splats_draw)
    drawn, path = cloud, getattr(args, "path", None)
    if basis_rows is None and not getattr(args, "full", False):
        from splatedit.render.splat.headless import drawn_for_view
        drawn, path = drawn_for_view(cloud, camera, args.size[1], path)
    render_to_png(drawn, args.output, size=args.size, camera=camera, basis=basis_rows, dC=d_c,
                  buffers_path=args.buffers, raster_path=path,
                  edl=getattr(args, "edl", False))
    print(f"wrote {args.output} ({args.size[0]}x{args.size[1]}, {cloud.n} splats"
          + (f", drawn as a level of {drawn.n} about a pixel wide (--full: every splat)"
             if drawn is not cloud else "")
          + (", deformed on the GPU" if basis_rows is not None else "") + ")"
          + (f" and {args.buffers}" if args.buffers else ""))
    return 0


def gpu_columns(edit) -> int:
    """Basis columns the renderer needs for ``edit`` (a script Edit): 4 per
    handle, one per point of each control curve of 2 points or more."""
    return 4 * len(edit.handles) + sum(len(c.points) for c in edit.curves if len(c.points) >= 2)


def check_gpu_columns(script_path) -> None:
    """Refuse, before any fitting, an edit script whose last edit (the one
    ``render --edit`` deforms on the GPU) needs more basis columns than the
    renderer holds (``RENDER_MAX_BASIS_COLUMNS``).

    Raises:
        EditScriptError: naming the script file and the edit's JSON path.
    """
    from splatedit.errors import EditScriptError
    from splatedit.script import load_script
    from splatedit.tolerances import RENDER_MAX_BASIS_COLUMNS
    edit = load_script(script_path).edits[-1]
    k = gpu_columns(edit)
    if k > RENDER_MAX_BASIS_COLUMNS:
        n_pts = sum(len(c.points) for c in edit.curves)
        raise EditScriptError(
            f"{len(edit.handles)} handle(s) and {n_pts} curve point(s) need {k} deformation columns on "
            f"the GPU (4 per handle, 1 per curve point), at most {RENDER_MAX_BASIS_COLUMNS}: split the "
            f"edit, or apply it with 'splatedit deform' and render the result",
            json_path=edit.json_path, path=str(script_path))


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
    from splatedit.render.gaussian.headless import render_gaussians_to_png
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
        from splatedit.tolerances import RENDER_MAX_BASIS_COLUMNS

        def gpu_can_draw(rows, d_c):
            return (isinstance(d_c, np.ndarray) and len(rows) == 5
                    and rows[1].shape[1] <= RENDER_MAX_BASIS_COLUMNS)

        _, basis_rows, d_c = _gpu_edit(args, proxy, on_gpu=gpu_can_draw)
        if not gpu_can_draw(basis_rows, d_c):
            # the Gaussian GPU pass draws a plain dC only: a turning handle (rotation mode) or the
            # detail mode is applied on the CPU as `splatedit deform` does, then drawn undeformed
            from splatedit.script.gaussian import run_script_gaussians
            cloud, _ = run_script_gaussians(cloud, load_script(args.edit), source=str(args.edit),
                                            progress=args.progress)
            basis_rows = d_c = None
            on_cpu = True
    render_gaussians_to_png(cloud, args.output, size=args.size, camera=camera, basis=basis_rows, dC=d_c,
                            path=getattr(args, "path", None) or "auto")
    how = ", deformed on the CPU" if on_cpu else ", deformed on the GPU" if basis_rows is not None else ""
    print(f"wrote {args.output} ({args.size[0]}x{args.size[1]}, {len(cloud)} Gaussians, SH degree "
          f"{cloud.sh_degree}{how})")
    return 0


def _splats_draw(rows, d_c) -> bool:
    """Whether the splat renderer draws this edit: not the frames of moved
    curves in the rotation mode (:mod:`splatedit.deform.curve_frames`; its GPU
    pass draws the paper's linear curve edit), which are applied on the CPU."""
    return not getattr(d_c, "curves", ())


def _gpu_edit(args, cloud, on_gpu=None):
    """Apply an edit script for rendering: every edit but the last is committed
    on the CPU (each edit's result is the next one's base); the last edit goes
    to the GPU as basis rows plus its control-frame displacement dC.
    ``on_gpu(rows, dC)``: whether the caller's renderer can draw them (else
    it deforms on the CPU, and the report says so).

    Returns (base cloud of the last edit, (indices, B, Bx, By, Bz), dC); a
    script ending with a delete / crop runs wholly on the CPU: (its result,
    None, None).
    """
    import dataclasses
    from splatedit.script import fit_edit, load_script, run_script
    script = load_script(args.edit)
    source = str(args.edit)
    from splatedit.script import Removal
    if isinstance(script.edits[-1], Removal):      # ends with a delete / crop: all of it on the CPU
        cloud, _ = run_script(cloud, script, source=source, progress=args.progress,
                              on_edit=lambda rep: print_edit(args, rep))
        return cloud, None, None
    if len(script.edits) > 1:
        head = dataclasses.replace(script, edits=script.edits[:-1])
        cloud, _ = run_script(cloud, head, source=source, progress=args.progress,
                              on_edit=lambda rep: print_edit(args, rep))
    resolved, basis, d_c = fit_edit(cloud, script.edits[-1], script.solver, source=source,
                                    progress=args.progress)
    args.progress.close()
    st = basis.stats
    mode = script.edits[-1].deformation.value
    detail = getattr(basis, "detail_for_gpu", None)   # the detail mode (splatedit.deform.detail)
    rows = basis.rows_for_gpu() + ((detail(),) if detail else ())
    gpu = on_gpu is None or on_gpu(rows, d_c)
    where = "uploaded to the GPU" if gpu else f"fitted; the {mode} edit is applied on the CPU"
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
    if on_gpu is _splats_draw and not detail and _would_refine(script.edits[-1], resolved, dist):
        # a far grab with needles in the rotation mode is refined when committed
        # (splatedit.deform.refine): drawn from the CPU as `splatedit deform` writes it
        from splatedit.deform.refine import refine_committed
        new, _, note = refine_committed(basis, cloud, basis.commit(cloud, d_c), script.edits[-1].deformation,
                                        resolved.matrices, dist)
        print(f"  {note or 'needles left as they are'}; the edit is applied on the CPU")
        return new, None, None
    if not gpu and on_gpu is _splats_draw:
        return basis.commit(cloud, d_c), None, None
    return cloud, rows, d_c


def _would_refine(edit, resolved, dist) -> bool:
    """Whether ``splatedit deform`` refines this edit (:func:`~splatedit.deform.refine.refine_committed`'s rule)."""
    from splatedit.deform.modes import DeformationMode
    from splatedit.deform.refine import is_translation, needs_refine
    return (edit.deformation is DeformationMode.ROTATION and is_translation(resolved.matrices, len(resolved.curves))
            and needs_refine(dist))

"""``splatedit convert`` and ``splatedit deform``: format conversion (with
optional outlier removal) and edit scripts applied on the CPU, to splat
clouds or Gaussian scenes; each edit's report line and warnings."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from splatedit.errors import ParameterError


def cmd_convert(args) -> int:
    """Run ``splatedit convert``: one file (format change, normals, sizes, outlier removal) or, for a folder
    or glob, a batch on Dask; returns the exit status."""
    from splatedit.commands.batch import cmd_convert_batch, is_batch_input
    if is_batch_input(args.input):
        return cmd_convert_batch(args)
    for opt in ("to", "workers", "scheduler", "independent"):
        if getattr(args, opt, None) not in (None, False):
            raise ParameterError(f"--{opt}", "applies to many tiles (INPUT a folder or a glob pattern)")
    from splatedit.io import check_output_path, is_gaussian_file, read, write
    check_output_path(args.output, overwrite=args.force, protect=args.input)
    if is_gaussian_file(args.input) and not args.to_splats and Path(args.output).suffix.lower() == ".ply":
        from splatedit.io import read_gaussians, write_gaussians
        if args.remove_outliers:
            raise ParameterError("--remove-outliers", "works on point clouds, not on Gaussian scenes")
        g = read_gaussians(args.input, progress=args.progress)
        write_gaussians(args.output, g, overwrite=args.force, up_axis=_kept_up(args.input))
        print(f"wrote {args.output}: {len(g)} Gaussians ({g.kind.value}, SH degree {g.sh_degree})")
        return 0
    from splatedit.io.formats import suffix_of
    if (suffix_of(args.output) == ".copc.laz" and suffix_of(args.input) in (".las", ".laz", ".copc.laz")
            and not args.remove_outliers):
        # streamed, in bounded memory (any size): splatedit.io.copc_convert.convert_to_copc
        from splatedit.io import check_readable_file
        from splatedit.io.copc_convert import convert_to_copc
        check_readable_file(args.input)
        rep = convert_to_copc(args.input, args.output, progress=args.progress)
        args.progress.close()
        print(f"wrote {args.output}: {rep.point_count} points in {rep.nodes} octree nodes (COPC)")
        return 0
    cloud = read(args.input, progress=args.progress)
    if args.remove_outliers:
        cloud = _remove_outliers(args, cloud)
    write(args.output, cloud, overwrite=args.force, up_axis=_kept_up(args.input))
    _z_up_output_note(cloud, args.input, args.output)
    print(f"wrote {args.output}: {cloud.n} splats" + _faces_note(cloud, args.output))
    return 0


def _kept_up(input_path) -> str | None:
    """The up axis the input names: its PLY header's ("+Z", ...; the editor
    writes it on save), else +Z for a Z-up format (LAS/LAZ, E57: scanner
    coordinates), so that a converted or deformed PLY copy opens standing the
    same way; None when the input says nothing."""
    from splatedit.io.formats import is_z_up
    from splatedit.model.orientation import header_up_hint
    hint = header_up_hint(input_path)
    if hint is not None:
        return hint.label
    return "+Z" if is_z_up(input_path) else None


def _z_up_output_note(cloud, input_path, output) -> None:
    """A ``splatedit: note:`` when ``output``'s format is read Z-up (LAS/LAZ,
    E57) but the model stands on another axis (as the editor and ``render``
    detect it for the input): the copy will open lying on its side.  The
    coordinates are written as they are (no silent rotation)."""
    from splatedit.io.formats import is_z_up
    from splatedit.model.orientation import detect_cloud_up_axis
    if not is_z_up(output) or is_z_up(input_path):
        return
    up = detect_cloud_up_axis(cloud, input_path)
    if up.label != "+Z":
        print(f"splatedit: note: {output}: {Path(output).suffix.lower()} files are read Z-up (scanner "
              f"coordinates), but this model's up axis is {up.label} ({up.source.value}): the copy will open "
              f"lying on its side (a .ply copy keeps {up.label})", file=sys.stderr)


def _faces_note(cloud, output) -> str:
    """What became of a mesh's faces in ``output``: kept (the registry's
    ``faces`` formats, :data:`splatedit.io.FACE_EXTENSIONS`: PLY, OFF) or
    dropped (the point formats)."""
    from splatedit.io import FACE_EXTENSIONS
    if cloud.faces is None:
        return ""
    ext = Path(output).suffix.lower()
    if ext in FACE_EXTENSIONS:
        return f", {len(cloud.faces)} faces"
    return (f" (the {len(cloud.faces)} faces were dropped: {ext} holds points only; "
            f"write {' or '.join(FACE_EXTENSIONS)} to keep them)")


def print_edit(args, rep) -> None:
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
                      on_edit=lambda rep: print_edit(args, rep))


def cmd_deform(args) -> int:
    """Run ``splatedit deform``: apply an edit script to a model and write the result (never over the
    input unless asked); returns the exit status."""
    from splatedit.io import check_output_path, check_readable_file, is_gaussian_file, read, write
    check_output_path(args.output, overwrite=args.force, protect=args.input)
    check_readable_file(args.edit)
    if is_gaussian_file(args.input):
        return _deform_gaussians(args)
    from splatedit.commands.outofcore import deform_copc, is_copc_path
    from splatedit.io.formats import suffix_of
    if suffix_of(args.output) == ".copc.laz" and is_copc_path(args.input):
        # out of core: the regions' nodes read, the rest copied compressed
        return deform_copc(args, lambda rep: print_edit(args, rep))
    cloud = read(args.input, progress=args.progress)
    t0 = time.perf_counter()
    out, reports = _run_edits(args, cloud, args.edit)
    write(args.output, out, overwrite=args.force, up_axis=_kept_up(args.input))
    print(f"wrote {args.output}: {out.n} splats, {len(reports)} edit(s) in {time.perf_counter() - t0:.2f} s")
    return 0


def _deform_gaussians(args) -> int:
    """``deform`` of a Gaussian scene: edits select centres; covariances and
    spherical harmonics follow the Jacobian; the output is a Gaussian PLY."""
    from splatedit.script.gaussian import run_script_gaussians
    from splatedit.io import read_gaussians, write_gaussians
    from splatedit.script import load_script
    if Path(args.output).suffix.lower() != ".ply":
        raise ParameterError("--output", f"{args.input} is a Gaussian scene: the output must be a .ply")
    script = load_script(args.edit)
    g = read_gaussians(args.input, progress=args.progress)
    t0 = time.perf_counter()
    out, reports = run_script_gaussians(g, script, method=args.method, tol=args.tol,
                                        source=str(args.edit), progress=args.progress,
                                        on_edit=lambda rep: print_edit(args, rep))
    write_gaussians(args.output, out, overwrite=args.force, up_axis=_kept_up(args.input))
    print(f"wrote {args.output}: {len(out)} Gaussians, {len(reports)} edit(s) in "
          f"{time.perf_counter() - t0:.2f} s")
    return 0

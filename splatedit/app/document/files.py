"""Files of the editor: checking the model before a window opens, the
default save path, the refusal to overwrite the opened model, the load /
save / export jobs (worker threads; the editor polls them), and opening
another model in the same window (:func:`open_path`: asks about unsaved
changes, loads in the background, keeps the old model when the new one
cannot be read, remembers the file in the recent files)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from splatedit.app.document.gaussian import gaussians_of, model_summary
from splatedit.app.document.jobs import Cancelled, Job
from splatedit.errors import InputError, SplatEditError
from splatedit.io.formats import extensions
from splatedit.tolerances import EDITOR_GUESS_MS_PER_SPLAT, EDITOR_LOD_BUDGETS, EDITOR_LOD_MIN_SPLATS


#: inputs saved in their own format (their scanner dimensions: intensity,
#: classification, the LAS scale/offset or E57 pose, survive); everything else
#: is saved as splatedit's lossless splat PLY (the formats marked
#: ``keep_on_save`` in :data:`splatedit.io.formats.FORMATS`)
KEEP_FORMAT_SUFFIXES = extensions(keep_on_save=True)


def package_folder() -> Path:
    """The folder of the installed ``splatedit`` package (resolved): the
    parent of its ``data`` folder (the shipped models)."""
    from splatedit.data import default_model_path
    return default_model_path().resolve().parent.parent


def inside_package(path) -> bool:
    """True when ``path`` is in the installed splatedit package's folder
    (its shipped models, ``splatedit/data/...``): files the editor opens but
    never writes beside (an upgrade would delete them, and the folder may be
    read-only or shared by every user of the installation)."""
    try:
        return Path(path).expanduser().resolve().is_relative_to(package_folder())
    except (OSError, RuntimeError):
        return False


def user_folder() -> Path:
    """Where a save of a bundled model goes, as other editors do with
    read-only or bundled files: the current directory, else (it is in the
    package, or not writable) the home folder."""
    cwd = Path.cwd()
    if not inside_package(cwd) and os.access(cwd, os.W_OK):
        return cwd
    return Path.home()


def default_save_path(src: Path | None, name: str, bundled: bool) -> Path:
    """``<stem>-edited.ply`` (``.las`` / ``.laz`` / ``.e57`` for such inputs)
    next to the input, never an existing file.  A model of the installed
    package (the bundled one, or any file opened from ``splatedit/data/...``,
    :func:`inside_package`) or one in an unwritable folder is saved in the
    user's folder instead (:func:`user_folder`): never into the package."""
    stem = Path(name).stem if name else (src.stem if src else "model")
    suffix = Path(name).suffix.lower() if name else (src.suffix.lower() if src else "")
    ext = suffix if suffix in KEEP_FORMAT_SUFFIXES else ".ply"
    if stem.lower().endswith(".copc") and suffix == ".laz":      # a COPC stays a COPC
        stem, ext = stem[:-5], ".copc.laz"
    folder = user_folder()
    if (src is not None and not bundled and not inside_package(src)
            and os.access(src.parent, os.W_OK)):
        folder = src.parent
    p = folder / f"{stem}-edited{ext}"
    k = 2
    while p.exists():
        p = folder / f"{stem}-edited-{k}{ext}"
        k += 1
    return p


def script_path_for(ply: Path) -> Path:
    return ply.with_suffix("").with_name(ply.with_suffix("").name + ".edits.json")


def _same_file(a, b) -> bool:
    try:
        return Path(a).expanduser().resolve() == Path(b).expanduser().resolve()
    except (OSError, RuntimeError):     # e.g. a symlink loop: compare the spellings
        return Path(a) == Path(b)


def save_refusal(target, model) -> str | None:
    """Why the editor refuses to save to ``target`` (None when it may): saves
    never replace the opened model (a user's file or the bundled one), nor
    does the edit script written beside the save, and nothing is written into
    the installed package's folder (:func:`inside_package`)."""
    if inside_package(target):
        return (f"not saved: {target} is inside the installed splatedit package ({package_folder()}); "
                "Ctrl+Shift+S: save in a folder of yours")
    if model is None:
        return None
    for path in (target, script_path_for(Path(target))):
        if _same_file(path, model):
            return (f"not saved: {path} is the opened model, which saves never replace "
                    "(Ctrl+Shift+S: save under another name)")
    return None


def check_model_file(path) -> None:
    """Refuse a model the editor could not open, before any window exists:
    missing, a directory, an extension :func:`splatedit.io.read` does not
    know, or unreadable.  Raises :class:`InputError` (one line, exit 2)."""
    from splatedit.io import READ_EXTENSIONS, split_scan_index
    p = Path(split_scan_index(path)[0])
    if not p.exists():
        raise InputError("no such file", path=str(path))
    if p.is_dir():
        raise InputError("is a directory, not a file", path=str(path))
    ext = p.suffix.lower()
    if ext not in READ_EXTENSIONS:
        raise InputError(f"unsupported file extension {ext or '(none)'!r} for reading; "
                         f"supported: {', '.join(READ_EXTENSIONS)}", path=str(path))
    from splatedit.io import check_readable_file
    check_readable_file(p)          # by stat: opening a FIFO would block before any window
    try:
        with open(p, "rb") as f:
            f.read(1)
    except OSError as exc:
        raise InputError(f"cannot read the file ({exc.strerror or exc})", path=str(path)) from None


def load_job(path: Path, wake, out_of_core: bool | None = None) -> Job:
    """Read ``path`` in the background (the job's ``key`` is the path).  Its
    result is the cloud, or (scan, cloud) for a scan opened out of core
    (:mod:`splatedit.app.document.outofcore`; ``out_of_core`` None: by its size)."""
    def work(progress):
        from splatedit.io import is_gaussian_file, read, read_gaussians
        from splatedit.app.document import outofcore
        if out_of_core or (out_of_core is None and outofcore.is_out_of_core(path)):
            return outofcore.open_scan(path, progress)
        if is_gaussian_file(path):      # a 3DGS/2DGS scene: its splat proxy with the Gaussians attached
            from splatedit.app.document.gaussian import gaussian_document
            scene = read_gaussians(str(path), progress=progress)
            scene.name = scene.name or path.name
            cloud = gaussian_document(scene)
        else:
            cloud = read(str(path), progress=progress)
        if not cloud.name:
            cloud.name = path.name
        return cloud
    return Job(f"loading {path.name}", work, wake, key=Path(path))


def open_path(ed, path, *, confirmed: bool = False) -> bool:
    """Open ``path`` in place of the current model (Ctrl+O, a dropped file,
    the GUI's File menu).  A file that cannot be opened shows an error box;
    with unsaved changes the editor asks first (``ed.confirm_open``) unless
    ``confirmed``.  Returns True when the load started."""
    p = Path(os.path.abspath(Path(path).expanduser()))
    try:
        check_model_file(p)
    except InputError as exc:
        ed.show_error(f"cannot open: {exc}")
        return False
    if "save" in ed.jobs:
        ed.show_error(f"cannot open {p.name} while a save is running: wait for it, then open again")
        return False
    if "load" in ed.jobs:              # the newest request wins
        ed.jobs.pop("load").cancel.set()
    s = ed.session
    if s is not None and s.dirty and not confirmed:
        ed.confirm_open = p
        ed.say(f"unsaved changes: press Y to open {p.name} without saving, N or Esc to stay")
        return False
    ed.confirm_open = None
    ed.jobs["load"] = load_job(p, ed.wake, getattr(ed, "out_of_core", None))
    ed.say(f"opening {p} ...")
    return True


def answer_open(ed, yes: bool) -> None:
    """The answer to "open without saving?": Y opens, anything else keeps the model."""
    path, ed.confirm_open = ed.confirm_open, None
    if yes:
        open_path(ed, path, confirmed=True)
    else:
        ed.say(f"not opened: {path.name} (the current model stays)")


def on_drop(ed, paths: list[Path]) -> None:
    """Files dropped on the window: open the first model (a folder: browse it)."""
    if not paths:
        return
    if ed.prompt is not None or ed.confirm_quit or ed.confirm_open is not None:
        ed.say("answer the open question first, then drop the file again")
        return
    ed.browser.close()
    first = paths[0]
    if len(paths) > 1:
        ed.say(f"{len(paths)} files dropped: opening only {first.name}")
    if first.is_dir():
        ed.file_actions.open_dialog(first)
    else:
        open_path(ed, first)


def _replace_session(ed, path: Path) -> None:
    """Before a newly loaded model takes over: close the old session, drop its
    levels of detail and per-model state (the camera is framed anew)."""
    old = ed.session
    lod = ed.jobs.pop("lod", None)
    if lod is not None:
        lod.cancel.set()
    ed.session = None
    if old is not None:
        old.close()
    ed.drag, ed.drag_tool = type(ed.drag).NONE, None
    ed.confirm_quit, ed.prompt = False, None
    ed.viewport.set_pyramid(None)
    ed.frames.invalidate()
    ed.path, ed.bundled = path, False
    ed.save_as = ed.saved_path = ed.saved_script = None
    for name in ("nodes", "region"):        # an out-of-core scan's jobs
        job = ed.jobs.pop(name, None)
        if job is not None:
            job.cancel.set()
    ed.ooc = None


def remember(ed, path: Path) -> None:
    """Put a user's model first in the recent files (not the bundled one)."""
    if ed.bundled or ed.recent is None:
        return
    try:
        ed.recent.add(path)
    except SplatEditError as exc:
        ed.say(f"recent files not kept: {exc}")


def save(ed, path: Path) -> None:
    """Start saving the session's cloud to ``path`` and its edit script beside
    it (``ed``: the editor, or anything with ``session``, ``jobs``, ``path``,
    ``say``, ``wake``)."""
    s = ed.session
    if "save" in ed.jobs:
        ed.say("a save is already running")
        return
    refusal = save_refusal(path, ed.path)
    if refusal:
        ed.say(refusal)
        return
    if getattr(ed, "ooc", None) is not None:          # a scan out of core: streamed, the edited nodes replaced
        from splatedit.app.document.outofcore import save_job
        ed.save_as = path
        ed.jobs["save"] = save_job(ed, ed.ooc, Path(path), script_path_for(Path(path)))
        ed.say(f"saving {path} ...")
        return
    cloud, script, pos = s.cloud, s.edit_script(), s.history.position
    ed.save_as = path
    spath = script_path_for(path)

    scene = gaussians_of(cloud)
    if scene is not None and Path(path).suffix.lower() != ".ply":
        ed.say(f"not saved: {path}: a Gaussian splatting scene is saved as a .ply")
        return

    # the up axis the user sees (detected or chosen with U) goes into a PLY's
    # header, so the saved file opens standing the same way
    up = ed.camera.up.label if getattr(ed, "camera", None) is not None else None

    def work(progress):
        from splatedit.io import write, write_gaussians
        progress("saving", 0.0)
        if scene is not None:       # the committed edits' Gaussians (covariances, SH rotated), extras kept
            write_gaussians(str(path), scene, overwrite=True, progress=progress, up_axis=up)
        else:
            write(str(path), cloud, overwrite=True, up_axis=up)
        script.save(spath)
        return path, spath, pos, s

    ed.jobs["save"] = Job("saving", work, ed.wake)
    ed.say(f"saving {path} ...")


def export_script(ed, target: Path) -> None:
    """Start writing only the edit script that belongs beside ``target``."""
    script = ed.session.edit_script()
    spath = script_path_for(target)

    def work(progress):
        script.save(spath)
        return spath

    ed.jobs["export"] = Job("exporting", work, ed.wake)


def on_loaded(ed, cloud, path: Path | None = None) -> None:
    """A model finished loading (from ``path``; None: ``ed.path``): it
    replaces the open one; a new session, camera and up axis, levels of detail."""
    if path is not None and (ed.session is not None or path != ed.path):
        _replace_session(ed, path)
        ed.cloud_name = path.name
    ed.cloud_name = cloud.name or ed.cloud_name
    from splatedit.app.document.session import Session
    ed.session = Session(cloud, method=ed.method, tol=ed.tol, max_centers=ed.max_centers,
                           on_change=ed.wake, graphs=ed.selection_tools)
    ed.viewport.set_cloud(cloud)
    # the heat map shows an edit's stretch: a freshly opened model has none (it
    # would draw as a flat grey silhouette), so it opens shaded
    ed.viewport.distortion_map = False
    scene = gaussians_of(cloud)      # a Gaussian scene: drawn by the Gaussian renderer, its own LOD
    if scene is None and cloud.n >= EDITOR_LOD_MIN_SPLATS and ed.viewport.ms_per_splat is None:
        # a first guess of the device's cost (lavapipe: ~0.5-1 us per splat at 720p) so
        # that a huge model's first full-quality frame is already drawn in the background
        w, h = ed.size
        ed.viewport.assume_cost(EDITOR_GUESS_MS_PER_SPLAT, max(w * h, 1))
    r = float(np.linalg.norm(cloud.positions.max(0) - cloud.positions.min(0))) / 2
    ed.cam.scene_radius = max(r, 1e-9)
    ed.camera.fresh_view(cloud, ed.path)
    ed.window.set_title(f"splatedit - {ed.cloud_name}")
    if ed.use_lod and scene is None and cloud.n >= EDITOR_LOD_MIN_SPLATS:
        def work(progress):
            from splatedit.model.lod import LodPyramid
            return LodPyramid(cloud, EDITOR_LOD_BUDGETS, progress=progress, background=True)   # preview first
        ed.jobs["lod"] = Job("levels of detail", work, ed.wake)
    ed.viewport.set_gaussian_lod(None)
    if ed.use_lod and scene is not None:
        def rank(progress):       # the Gaussians' ranking for moving frames (the model module's)
            from splatedit.model.gaussian_lod import build_gaussian_lod
            return build_gaussian_lod(scene, progress=progress)
        ed.jobs["lod"] = Job("Gaussian level of detail", rank, ed.wake)
    ed.selection_tools.prepare(cloud)
    guard = getattr(ed, "crash_guard", None)
    if guard is None or guard.restoring is None:      # a recovery file is not a recent model
        remember(ed, ed.path)
    what = model_summary(cloud)
    note = ed.camera.extent().note()
    ed.say(f"loaded {ed.cloud_name}: {what} (up axis {ed.camera.up.label}, "
           f"{ed.camera.up.source.value}; U changes it)" + (f"; {note}" if note else ""))


def poll_jobs(ed) -> None:
    """Collect the editor's finished jobs (load, levels of detail, save, export, graph)."""
    for name, job in list(ed.jobs.items()):
        if not job.done:
            continue
        del ed.jobs[name]
        land = getattr(job, "land", None)
        if land is not None:          # a tool's job (ToolContext.start_job) lands itself
            land(job)
            continue
        if job.error is not None:
            err = job.error
            if name == "graph":
                if not isinstance(err, Cancelled):
                    ed.say(f"{job.name} failed: {err}")
                ed.selection_tools.poll()
                continue
            if isinstance(err, Cancelled):
                continue
            if name == "load" and ed.session is None and job.key == ed.path:
                # the first model: reported by run_editor's caller as any bad input
                ed.load_error = err if isinstance(err, SplatEditError) else SplatEditError(
                    f"{ed.path}: cannot read the model: {err}")
                ed.exit_code = 2
                ed.running = False
            elif name == "load":       # another model: the open one stays
                if getattr(ed, "crash_guard", None) is not None:
                    ed.crash_guard.restoring = None
                text = str(err) if isinstance(err, SplatEditError) else f"{job.key}: cannot read the model: {err}"
                ed.show_error(f"not opened: {text}")
            elif name in ("save", "export"):
                ed.show_error(f"{job.name} failed: {err}")
            elif name == "region" and ed.session is not None:
                ed.session.waiting = None
                ed.show_error(f"{job.name} failed: {err}")
            else:
                ed.say(f"{job.name} failed: {err}")
            continue
        if name == "load":
            result = job.result
            if isinstance(result, tuple):       # (scan, cloud): out of core
                scan, result = result
                ed.file_actions.on_loaded(result, job.key)
                ed.ooc = scan
                ed.session.splats_fixed = "not for a scan opened out of core (every point stays in its file)"
                ed.say(f"opened {ed.cloud_name} out of core: {scan.copc.point_count:,} points, "
                       f"{result.n:,} shown; the view refines where the camera looks")
            else:
                ed.ooc = None
                ed.file_actions.on_loaded(result, job.key)
            guard = getattr(ed, "crash_guard", None)
            entry = None if guard is None else guard.restoring
            if entry is not None and Path(job.key) == Path(os.path.abspath(entry.model)):
                guard.on_restored()         # a recovery entry: its edits and source come with it
        elif name in ("nodes", "region"):
            if getattr(ed, "ooc", None) is not None:
                ed.ooc.landed(ed, name, job.result)
        elif name == "lod" and hasattr(job.result, "rank"):      # a GaussianLod
            ed.viewport.set_gaussian_lod(job.result)
            ed.say(f"level of detail ready (moving: up to {job.result.m:,} of {job.result.n:,} Gaussians)")
        elif name == "lod":
            ed.viewport.set_pyramid(job.result)
            counts = ", ".join(f"{lvl.n:,}" for lvl in job.result.levels)
            more = "" if job.result.ready.is_set() else "; the finer ones are being built"
            ed.say(f"levels of detail ready ({counts} splats{more})")
        elif name == "save":
            ply, script, pos, saved_session = job.result
            if ed.session is not saved_session:     # another model was opened meanwhile
                ed.say(f"saved {ply} and {script.name} (the model opened since is not saved)")
                continue
            ed.session.history.mark_saved(pos)
            if getattr(ed, "crash_guard", None) is not None:
                ed.crash_guard.restored_saved(saved_session)
            ed.saved_path, ed.saved_script = ply, script
            ed.say(f"saved {ply} and {script.name}")
        elif name == "export":
            ed.saved_script = job.result
            ed.say(f"edit script written to {job.result}")
        elif name == "graph":
            graphs = ed.selection_tools
            if graphs.poll() and graphs.closure_pending and ed.session is not None:
                added = ed.session.selection_edit.close_pending()    # the selection waiting for it
                if added:
                    ed.say(f"closure added {added:,} splats")

"""Command line: ``splatedit [demo|edit|info|convert|deform|render|bench] ...``.

Bad input (files, edit scripts, parameters) prints one line ``splatedit: error: ...``
to stderr and exits with code 2, without a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import sys
import threading
import warnings
from pathlib import Path

# numpy asks for transparent huge pages on large arrays; where the kernel
# then compacts memory on the first touch (THP defrag "madvise", as here)
# filling 720 MB of new arrays took 2.6-3.5 s instead of 0.8-1.1 s, most of a
# 10M-splat read.  Set before numpy is imported (the user's setting wins)
os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")

from splatedit.app.ui.options import join_negative_values, parse_size, positive_float
from splatedit.bench.runner import BENCHES
from splatedit.commands.edits import cmd_convert, cmd_deform
from splatedit.commands.info import cmd_info
from splatedit.commands.render import cmd_render
from splatedit.errors import InputWarning, ParameterError, SplatEditError

#: the `splatedit bench` cases (one JSON line per case each)
BENCH_NAMES = tuple(BENCHES)

EXIT_BAD_INPUT = 2
#: 128 + SIGINT, for Ctrl+C, SIGTERM and SIGHUP alike
EXIT_INTERRUPTED = 130
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
def cmd_demo(args) -> int:
    """Run ``splatedit demo``: the headless tour into ``args.output_dir``; returns the exit status."""
    from splatedit.commands.demo import run_demo
    run_demo(Path(args.output_dir), progress=args.progress, log=print, render=not args.no_render,
             overwrite=args.force)
    return 0


def cmd_edit(args) -> int:
    """Run ``splatedit edit``: check the paths first, then open the editor window; returns the exit status."""
    check_edit_paths(args.file, args.save_as)       # before the editor opens a window
    from splatedit.app.editor import run_editor
    from splatedit.app.ui.options import options_from_args
    return run_editor(args.file, **options_from_args(args))


def check_edit_paths(model, save_as) -> None:
    """The checks ``splatedit edit`` makes before any window, the same the
    other commands make: the model must be a readable regular file of a known
    format (:func:`splatedit.app.document.files.check_model_file`: a FIFO is refused
    by stat, never opened, as opening it blocks until a writer comes), and
    ``--save-as`` a writable target of a format the editor writes (its
    folder exists; it may replace an older save).

    Raises:
        InputError / ParameterError: one line, exit 2.
    """
    from splatedit.io import WRITE_EXTENSIONS, check_output_path
    if model is not None:
        from splatedit.app.document.files import check_model_file
        check_model_file(model)
    if save_as:
        try:
            check_output_path(save_as, overwrite=True, extensions=WRITE_EXTENSIONS)
        except SplatEditError as exc:
            raise ParameterError("--save-as", str(exc)) from None


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
    """Run ``splatedit bench WHAT``: one JSON line per benchmark case on stdout; returns the exit status."""
    from splatedit.bench.runner import run_bench
    what = args.what
    if args.gaussians:
        if what != "render":
            raise ParameterError("--gaussians", f"applies to 'bench render', not 'bench {what}'")
        what = "gaussian-render"
    from splatedit.bench.runner import SIZED
    if args.size is not None and what not in SIZED + ("render",):
        raise ParameterError("--size", f"applies to 'bench render / {' / '.join(SIZED)}', not 'bench {what}'")
    if args.path is not None and what not in SIZED:
        raise ParameterError("--path", f"applies to 'bench {' / '.join(SIZED)}', not 'bench {what}' "
                                       "(bench render compares both paths in every case)")
    if args.model and what != "render":
        raise ParameterError("--model", f"applies to 'bench render', not 'bench {what}'")
    for line in run_bench(what, quick=args.quick, progress=args.progress, counts=args.splats, large=args.large,
                          size=args.size, path=args.path, models=args.model):
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
    """The ``splatedit`` argument parser with every subcommand (its errors follow the one-line error contract)."""
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

    from splatedit.io import READ_EXTENSIONS, WRITE_EXTENSIONS    # the format registry's lists
    s = sub.add_parser("convert", help=f"convert by extension: reads {' '.join(READ_EXTENSIONS)}, writes "
                                       f"{' '.join(WRITE_EXTENSIONS)} (estimates normals and sizes when "
                                       "missing); a Gaussian splatting PLY stays one (see --to-splats)")
    s.add_argument("input")
    s.add_argument("output")
    s.add_argument("--to-splats", action="store_true",
                   help="Gaussian input: write plain splats (lossy: a disc per Gaussian from its two "
                        "largest axes at 2 sigma, colour from the DC term)")
    s.add_argument("--remove-outliers", action="store_true",
                   help="drop statistical and isolated outlier points (point clouds only)")
    s.add_argument("-f", "--force", action="store_true", help="overwrite OUTPUT if it exists")
    s.add_argument("--to", metavar="EXT", help="many tiles (INPUT a folder or a quoted glob, OUTPUT a folder): "
                                               "the output format, e.g. .laz (default .ply)")
    s.add_argument("--workers", type=_positive_count, metavar="N",
                   help="many tiles: parallel tasks on the local scheduler (default: one per core)")
    s.add_argument("--scheduler", metavar="ADDRESS",
                   help="many tiles: 'threads' (default), 'processes', or a Dask distributed "
                        "scheduler's address (tcp://HOST:PORT; the workers must see the files)")
    s.add_argument("--independent", action="store_true",
                   help="many files: separate models, not tiles of one scan (no halo across their borders)")
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
                   help="camera position (default: the editor's first view, see docs/commands.md)")
    s.add_argument("--target", type=lambda t: _parse_vec3(t, "--target"), metavar="X,Y,Z",
                   help="look-at point (default: the centre of the model's main body)")
    s.add_argument("--up", type=lambda t: _parse_vec3(t, "--up"), metavar="X,Y,Z",
                   help="up direction (default: the model's detected up axis, as in the editor)")
    s.add_argument("--fov", type=float, default=None, help="vertical field of view in degrees")
    s.add_argument("--edit", type=Path, help="apply this edit script on the GPU before rendering")
    s.add_argument("--buffers", help="also save depth/normal/weight/color float arrays to this .npz")
    s.add_argument("--edl", action="store_true",
                   help="eye-dome lighting: darken depth edges (scans without good normals; point-splat models)")
    s.add_argument("--path", choices=("auto", "raster", "compute"), default=None,
                   help="draw path: raster passes or compute shaders (splats: default env var SPLATEDIT_RASTER, "
                        "else auto: the faster, measured; Gaussian scenes: quads or the compute tile "
                        "rasterizer, default the device's, see docs/PERFORMANCE.md)")
    s.add_argument("--full", action="store_true",
                   help="draw every splat (default: where many splats fall in one pixel, a level of "
                        "detail whose splats are about a pixel wide, see docs/commands.md)")
    s.add_argument("-f", "--force", action="store_true", help="overwrite outputs")
    s.set_defaults(func=cmd_render)

    from splatedit.app.ui.options import CONTROLS, add_arguments
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
                   help="point/splat counts of estimate, render, editor, closure and the Gaussian benches, "
                        "support splats of basis and of solve's grab cases (on a cloud 2.5x as large) "
                        "(e.g. --splats 1000000 10000000)")
    s.add_argument("--large", action="store_true",
                   help="io: also the 10M-splat PLY read (writes an 840 MB file to the temp folder) and "
                        "whole 'info' and 'render' processes of a 10M normals + radius PLY (280 MB) "
                        "beside Open3D's read (SPLATEDIT_OPEN3D_PYTHON: its interpreter)")
    s.add_argument("--size", type=parse_size, default=None,
                   help="render, gaussian-render: image WxH (default 1280x720, 640x360 with --quick)")
    s.add_argument("--path", choices=("raster", "compute"), default=None,
                   help="gaussian-render: only this draw path (default: both, compared in the same run)")
    s.add_argument("--model", action="append", default=[], metavar="FILE",
                   help="render: also this model (e.g. a real scan); repeatable")
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
    """The console entry point: parse ``argv`` (default ``sys.argv[1:]``), run the command, map errors to one
    ``splatedit: error: ...`` line and exit status 2; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(join_negative_values(sys.argv[1:] if argv is None else list(argv), VECTOR_OPTIONS))
    args.progress = _Progress(enabled=not args.quiet)
    func = getattr(args, "func", cmd_main)
    restore = _signals_as_interrupt(final=argv is None)
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
        _ignore_signals()       # a second Ctrl+C / SIGTERM during the clean-up: no traceback
        args.progress.close()
        print("splatedit: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except MemoryError:
        # a reader or library asked for more than there is (the readers bound
        # what headers declare by the file size; this is the net behind them)
        args.progress.close()
        print("splatedit: error: not enough memory for this input "
              "(a smaller model or image, or more memory)", file=sys.stderr)
        return EXIT_BAD_INPUT
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


#: the signals handled like Ctrl+C: the terminal closed (SIGHUP), ``kill``
#: (SIGTERM) and Ctrl+C itself
_INTERRUPTS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))
#: the signal numbers received during this run
_RECEIVED: list[int] = []


def _ignore_signals() -> None:
    """Ignore further interrupts (main thread only): the first one is being
    handled (temporary files removed, one line printed); a second one 10 ms
    later must not raise inside that clean-up.  A Python handler that does
    nothing, not SIG_IGN: a signal already pending when the handler changes
    to SIG_IGN makes Python print "OSError: Signal 2 ignored due to race
    condition" with a traceback."""
    if threading.current_thread() is threading.main_thread():
        for sig in _INTERRUPTS:
            with contextlib.suppress(OSError, ValueError):
                signal.signal(sig, _note_signal)


def _note_signal(signum, frame):
    _RECEIVED.append(signum)


def _raise_interrupt(signum, frame):
    _RECEIVED.append(signum)
    if len(_RECEIVED) > 1:      # a second signal before the first's KeyboardInterrupt was handled
        return
    _ignore_signals()
    raise KeyboardInterrupt


def _signals_as_interrupt(final: bool = False):
    """Handle SIGINT, SIGTERM and SIGHUP alike: KeyboardInterrupt once
    (temporary files are removed, the target is untouched, exit code
    ``EXIT_INTERRUPTED``), then further ones are ignored.  Returns a
    function that puts the previous handlers back (a no-op outside the main
    thread, where signal handlers cannot be set); with ``final`` (the real
    command line, the process ends right after) further interrupts are
    ignored once one came, so one arriving during the interpreter's exit is
    harmless."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    _RECEIVED.clear()
    previous = {}
    for sig in _INTERRUPTS:
        previous[sig] = signal.signal(sig, _raise_interrupt)

    def restore():
        if final and _RECEIVED:
            # the process ends now: ignore further interrupts, since Python's
            # finalisation puts SIG_DFL back for every Python handler and one
            # arriving then would kill the process (-2 / -15 instead of 130).
            # signal.signal runs pending Python handlers (_note_signal) before
            # it changes one; after the change the OS drops new ones
            for sig in _INTERRUPTS:
                with contextlib.suppress(OSError, ValueError):
                    signal.signal(sig, signal.SIG_IGN)
            return
        for sig, handler in previous.items():
            signal.signal(sig, handler if handler is not None else signal.SIG_DFL)
    return restore


if __name__ == "__main__":
    sys.exit(main())

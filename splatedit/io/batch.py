"""Batch conversion of scan tiles on Dask: the engine of ``splatedit convert DIR|GLOB OUTDIR``
(the command itself, its lines and exit code, is :mod:`splatedit.commands.batch`).

Each tile is converted as ``splatedit convert`` converts one file (normals
and splat sizes where the file lacks them, optional outlier removal, the
format of the output extension), with one difference at the tile borders:
normals, sizes and outlier statistics are computed over the tile's own
points *and* its neighbour tiles' points within a halo of
``TILE_HALO_NEIGHBOURHOODS`` neighbourhood radii of its box, and only its own
points are written.  So a point near a seam gets the neighbours it would
have in the merged cloud, and its normal and size equal (within the figures
of docs/PERFORMANCE.md) those of converting the merged cloud at once.

The work runs in two Dask phases:

1. every tile is read (:func:`splatedit.io.read_columns`: the file's
   columns, nothing estimated yet) and measured (its box and neighbourhood
   radius); the tiles stay in the workers' memory;
2. for every tile, the halo bands of its neighbours (the points of tile j
   within tile i's box grown by the halo) and then its conversion, written
   atomically (:func:`splatedit.io.write`) into the output folder.

The scheduler is Dask's local thread pool by default (measured against its
process pool in docs/PERFORMANCE.md: the estimation's numpy and scipy calls
release the GIL, and processes pay for moving the tiles), its process pool
with ``--scheduler processes``, or a Dask distributed cluster with
``--scheduler tcp://HOST:PORT`` (every worker must see the input and output
paths, e.g. on a shared file system, and have splatedit installed).

Files that are separate models rather than tiles of one scan (``--independent``)
get no halo: each is converted exactly as ``splatedit convert FILE OUT``.

A tile that fails (unreadable, malformed, unwritable) is reported by name
and the others are still written; the command's exit code is then 2.
"""

from __future__ import annotations

import glob
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from splatedit.errors import ParameterError, SplatEditError

#: characters that make ``convert``'s input a glob pattern
GLOB_CHARS = "*?["
#: the local schedulers (Dask's names); anything else is a distributed scheduler's address
LOCAL_SCHEDULERS = ("threads", "processes", "synchronous")
DEFAULT_SCHEDULER = "threads"
DEFAULT_OUTPUT_EXTENSION = ".ply"


def is_batch_input(spec: str) -> bool:
    """True when ``convert``'s input names many tiles: a folder or a glob pattern."""
    return os.path.isdir(spec) or (any(c in spec for c in GLOB_CHARS) and not os.path.exists(spec))


def expand_inputs(spec: str) -> list[Path]:
    """The tiles named by a folder (its files with a readable extension, not
    recursive) or a glob pattern (``**`` recurses), sorted by path.

    Raises:
        ParameterError: nothing matches.
    """
    from splatedit.io import READ_EXTENSIONS
    if os.path.isdir(spec):
        files = [p for p in Path(spec).iterdir() if p.is_file() and p.suffix.lower() in READ_EXTENSIONS]
        what = f"folder {spec} holds no file with a readable extension ({', '.join(READ_EXTENSIONS)})"
    else:
        files = [Path(p) for p in glob.glob(spec, recursive=True) if os.path.isfile(p)]
        what = f"no file matches {spec!r}"
    if not files:
        raise ParameterError("input", what)
    return sorted(files)


@dataclass(frozen=True)
class TileJob:
    """One tile: its input file and the output file derived from it."""
    index: int
    src: Path
    out: Path


def plan_jobs(inputs: list[Path], out_dir: str | Path, ext: str, *, overwrite: bool) -> list[TileJob]:
    """Output names ``OUT_DIR/<input stem><ext>``, checked before any work.

    Raises:
        ParameterError: two inputs would give the same output, or an output
            is one of the inputs.
        InputError: an output exists (without ``overwrite``) or its folder is
            not writable (:func:`splatedit.io.check_output_path`).
    """
    from splatedit.io import check_output_path
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise ParameterError("output", f"{out_dir} is not a folder (converting many tiles writes one file each)")
    out_dir.mkdir(parents=True, exist_ok=True)
    ext = ext if ext.startswith(".") else "." + ext
    sources = {p.resolve() for p in inputs}
    jobs, seen = [], {}
    for i, src in enumerate(inputs):
        out = out_dir / (src.stem + ext.lower())
        key = out.resolve()
        if key in seen:
            raise ParameterError("output", f"{seen[key]} and {src} would both be written to {out}; "
                                           f"convert them into separate folders")
        if key in sources:
            raise ParameterError("output", f"{out} is one of the inputs: choose another output folder")
        seen[key] = src
        check_output_path(out, overwrite=overwrite, protect=src)
        jobs.append(TileJob(i, src, out))
    return jobs


# ------------------------------------------------------------------ tasks
@dataclass
class Tile:
    """A tile read by phase 1: its columns, world box and neighbourhood radius."""
    source: str
    columns: object = None              # splatedit.io.PointColumns
    lo: Optional[np.ndarray] = None     # (3,) world box
    hi: Optional[np.ndarray] = None
    reach: float = 0.0                  # model units
    error: Optional[str] = None


@dataclass
class TileResult:
    """What became of one tile (``error`` None: written)."""
    job: TileJob
    written: int = 0
    removed: int = 0
    halo: int = 0
    seconds: float = 0.0
    error: Optional[str] = None
    notes: list = field(default_factory=list)


def _message(src, exc: BaseException) -> str:
    """An error message that names the tile's file."""
    text = str(exc) if isinstance(exc, SplatEditError) else f"{type(exc).__name__}: {exc}"
    return text if str(src) in text else f"{src}: {text}"


def neighbourhood_reach(positions: np.ndarray, seed: int = 0) -> float:
    """Median distance (model units) from a seeded sample of
    ``TILE_SPACING_SAMPLE`` points to their ``SIZE_NEIGHBOURS``-th neighbour:
    how far the estimation of one splat looks."""
    from scipy.spatial import cKDTree
    from splatedit.tolerances import SIZE_NEIGHBOURS, TILE_SPACING_SAMPLE
    n = len(positions)
    if n < 2:
        return 0.0
    k = min(SIZE_NEIGHBOURS, n - 1)
    take = np.random.default_rng(seed).choice(n, size=min(n, TILE_SPACING_SAMPLE), replace=False)
    d, _ = cKDTree(positions).query(positions[take], k=k + 1)
    return float(np.median(d[:, k]))


def load_tile(src: str) -> Tile:
    """Phase 1: read a tile's columns (no estimation) and measure it; a
    failure is kept in ``error`` (a message naming the file)."""
    from splatedit.io import is_gaussian_file, read_columns
    try:
        if is_gaussian_file(src):
            return Tile(src, error=f"{src}: a Gaussian splatting scene; batch conversion takes point clouds "
                                  f"(convert it alone: `splatedit convert {src} OUT.ply`)")
        cols = read_columns(src)
        world_lo = cols.positions.min(axis=0) + cols.origin
        world_hi = cols.positions.max(axis=0) + cols.origin
        reach = neighbourhood_reach(cols.positions) if cols.needs_estimation() else 0.0
        return Tile(src, cols, world_lo, world_hi, reach)
    except Exception as exc:        # noqa: BLE001 - one bad tile must not stop the others
        return Tile(src, error=_message(src, exc))


def halo_band(tile: Tile, lo, hi) -> tuple:
    """Phase 2: ``tile``'s points inside the box ``lo``..``hi`` (world,
    already grown by the halo): ((m, 3) world positions, (m, 3) normals or
    None, (m,) radii or None)."""
    cols = tile.columns
    lo_l = np.asarray(lo) - cols.origin
    hi_l = np.asarray(hi) - cols.origin
    p = cols.positions
    inside = np.all((p >= lo_l) & (p <= hi_l), axis=1)
    pick = lambda a: None if a is None else np.asarray(a)[inside]     # noqa: E731
    return p[inside] + cols.origin, pick(cols.normals), pick(cols.radius)


def _concat_optional(own, parts, m: int, fill) -> Optional[np.ndarray]:
    """``own`` followed by each band's column (``fill(rows)`` where a band lacks it)."""
    if own is None:
        return None
    pieces = [np.asarray(own, dtype=np.float64)]
    for col, rows in parts:
        pieces.append(np.asarray(col, dtype=np.float64) if col is not None else fill(rows))
    return np.concatenate(pieces) if len(pieces) > 1 else pieces[0]


def convert_tile(job: TileJob, tile: Tile, bands: list, remove_outliers: bool, overwrite: bool) -> TileResult:
    """Phase 2: estimate what the tile lacks over its points and its halo
    ``bands`` (from :func:`halo_band`), optionally drop outliers (flagged
    over tile and halo), and write the tile's own points to ``job.out``."""
    from splatedit.io import cloud_from_columns, write
    t0 = time.perf_counter()
    result = TileResult(job)
    try:
        if tile.error is not None:
            result.error = tile.error
            return result
        cols = tile.columns
        n = cols.n
        bands = [b for b in bands if b is not None and len(b[0])]
        halo = (np.concatenate([b[0] for b in bands]) - cols.origin) if bands else np.zeros((0, 3))
        result.halo = len(halo)
        if cols.needs_estimation():
            from splatedit.model.estimate import estimate_splats
            pos = np.concatenate([cols.positions, halo])
            nrm = _concat_optional(cols.normals, [(b[1], len(b[0])) for b in bands], n,
                                   lambda m: np.zeros((m, 3)))         # zero rows get PCA normals
            rad = None
            if cols.radius is not None:
                fill = float(np.median(cols.radius))
                rad = _concat_optional(cols.radius, [(b[2], len(b[0])) for b in bands], n,
                                       lambda m: np.full(m, fill))
            est = estimate_splats(pos, nrm, None, radius=rad)
            cols = cols.with_axes(est.u[:n], est.v[:n])
        cloud = cloud_from_columns(cols)
        if remove_outliers:
            if cloud.faces is not None:
                raise ParameterError("--remove-outliers", f"{job.src} is a triangle mesh "
                                     f"({len(cloud.faces)} faces); outlier removal works on point clouds only")
            from splatedit.model.outliers import detect_outliers, stray_clusters
            pos = np.concatenate([cloud.positions, halo])
            flags = detect_outliers(pos)
            strays = stray_clusters(pos, flags.isolation_radius) & ~flags.mask
            drop = (flags.mask | strays)[:n]
            result.removed = int(drop.sum())
            if drop.any():
                cloud = cloud.subset(~drop)
        if cloud.faces is not None and job.out.suffix.lower() not in (".ply", ".off"):
            result.notes.append(f"its {len(cloud.faces)} faces were dropped ({job.out.suffix} holds points only)")
        write(job.out, cloud, overwrite=overwrite)
        result.written = cloud.n
    except Exception as exc:        # noqa: BLE001 - reported by name, the other tiles go on
        result.error = _message(job.src, exc)
    result.seconds = time.perf_counter() - t0
    return result


# ------------------------------------------------------------------ planning
def _neighbours(tiles: list[Tile]) -> list[list[tuple[int, np.ndarray, np.ndarray]]]:
    """For every tile i: (j, lo, hi) of each other tile j whose box comes
    within the halo of i's box, with i's box grown by that halo."""
    from splatedit.tolerances import TILE_HALO_NEIGHBOURHOODS
    good = np.array([i for i, t in enumerate(tiles) if t.error is None and t.columns.needs_estimation()],
                    dtype=np.int64)
    out = [[] for _ in tiles]
    if len(good) < 2:
        return out
    lo = np.array([tiles[i].lo for i in good])
    hi = np.array([tiles[i].hi for i in good])
    reach = np.array([tiles[i].reach for i in good])
    for a, i in enumerate(good):                # vectorised over the other tiles j
        h = TILE_HALO_NEIGHBOURHOODS * np.maximum(reach[a], reach)
        near = np.all(hi >= lo[a] - h[:, None], axis=1) & np.all(lo <= hi[a] + h[:, None], axis=1)
        near[a] = False
        for b in np.flatnonzero(near):
            out[i].append((int(good[b]), lo[a] - h[b], hi[a] + h[b]))
    return out


@dataclass
class BatchOptions:
    """How a batch conversion runs: outlier removal, overwriting, the Dask scheduler (``"local"`` or an
    address), the worker count (None: one per core) and whether tiles share an overlap halo."""
    remove_outliers: bool = False
    overwrite: bool = False
    scheduler: str = DEFAULT_SCHEDULER
    workers: Optional[int] = None
    #: False: the files are separate models (``--independent``), no halo
    halo: bool = True


def run_batch(jobs: list[TileJob], opts: BatchOptions,
              on_result: Optional[Callable[[TileResult], None]] = None) -> list[TileResult]:
    """Convert every tile of ``jobs`` on Dask (see the module docstring).

    Args:
        jobs: from :func:`plan_jobs`.
        opts: outlier removal, overwrite, scheduler (``threads``,
            ``processes``, ``synchronous`` or a distributed scheduler's
            address) and worker count (local schedulers; None: one per core).
        on_result: called with each tile's result as it finishes (in the
            calling thread).
    Returns:
        the results in ``jobs`` order.
    """
    on_result = on_result or (lambda r: None)
    if opts.scheduler in LOCAL_SCHEDULERS:
        return _run_local(jobs, opts, on_result)
    return _run_distributed(jobs, opts, on_result)


def _run_local(jobs, opts, on_result) -> list[TileResult]:
    import dask
    from dask.callbacks import Callback
    kw = dict(scheduler=opts.scheduler)
    if opts.workers and opts.scheduler != "synchronous":
        kw["num_workers"] = int(opts.workers)
    loads = [dask.delayed(load_tile, pure=False)(str(j.src), dask_key_name=f"load-{j.index}") for j in jobs]
    tiles = list(dask.compute(*loads, **kw))
    held = [dask.delayed(t, name=f"tile-{i}", traverse=False) for i, t in enumerate(tiles)]
    results: dict[int, TileResult] = {}
    tasks = []
    for job, nbs in zip(jobs, _neighbours(tiles) if opts.halo else [[] for _ in tiles]):
        bands = [dask.delayed(halo_band, pure=False)(held[j], lo, hi, dask_key_name=f"band-{job.index}-{j}")
                 for j, lo, hi in nbs]
        tasks.append(dask.delayed(convert_tile, pure=False)(job, held[job.index], bands, opts.remove_outliers,
                                                            opts.overwrite, dask_key_name=f"convert-{job.index}"))

    class _PerTile(Callback):
        def _posttask(self, key, result, dsk, state, worker_id):
            if isinstance(key, str) and key.startswith("convert-"):
                results[result.job.index] = result
                on_result(result)

    with _PerTile():
        done = dask.compute(*tasks, **kw)
    for r in done:
        if r.job.index not in results:          # (a callback missed: report it now)
            results[r.job.index] = r
            on_result(r)
    return [results[j.index] for j in jobs]


def _run_distributed(jobs, opts, on_result) -> list[TileResult]:
    try:
        from distributed import Client, as_completed
    except ImportError as exc:      # pragma: no cover - distributed is a dependency
        raise ParameterError("--scheduler", f"needs the 'distributed' package ({exc})") from None
    try:
        client = Client(opts.scheduler, timeout="10s", set_as_default=False)
    except (OSError, ValueError, TimeoutError) as exc:
        raise ParameterError("--scheduler", f"cannot reach a Dask scheduler at {opts.scheduler!r}: {exc}") from None
    try:
        tile_f = [client.submit(load_tile, str(j.src), key=f"load-{j.index}-{os.getpid()}-{time.time_ns()}",
                                pure=False) for j in jobs]
        # the boxes and radii only: the points stay on the workers
        meta = client.gather([client.submit(_tile_meta, f, pure=False) for f in tile_f])
        tasks = []
        for job, nbs in zip(jobs, _neighbours(meta) if opts.halo else [[] for _ in meta]):
            bands = [client.submit(halo_band, tile_f[j], lo, hi, pure=False) for j, lo, hi in nbs]
            tasks.append(client.submit(convert_tile, job, tile_f[job.index], bands, opts.remove_outliers,
                                       opts.overwrite, pure=False))
        results = {}
        with client.as_current():
            for fut in as_completed(tasks):
                r = fut.result()
                results[r.job.index] = r
                on_result(r)
        return [results[j.index] for j in jobs]
    finally:
        client.close()


def _tile_meta(tile: Tile) -> Tile:
    """A tile without its points (what the client needs to plan the halos)."""
    meta = Tile(tile.source, None, tile.lo, tile.hi, tile.reach, tile.error)
    if tile.columns is not None:
        meta.columns = _Estimates(tile.columns.needs_estimation())
    return meta


@dataclass
class _Estimates:
    """Stands in for a tile's columns in the client's plan: only whether it needs estimation."""
    flag: bool

    def needs_estimation(self) -> bool:
        return self.flag

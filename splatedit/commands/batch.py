"""``splatedit convert DIR|GLOB OUTDIR``: many scan tiles at once on Dask
(the engine, with the halo across tile seams: :mod:`splatedit.io.batch`)."""

from __future__ import annotations

import sys
import time

from splatedit.errors import ParameterError
from splatedit.io.batch import (DEFAULT_OUTPUT_EXTENSION, DEFAULT_SCHEDULER, BatchOptions, TileResult,
                                expand_inputs, is_batch_input, plan_jobs, run_batch)

__all__ = ["cmd_convert_batch", "is_batch_input"]


# ------------------------------------------------------------------ command
def cmd_convert_batch(args) -> int:
    """``splatedit convert DIR|GLOB OUTDIR``: one line per tile on stdout as
    it finishes, one ``splatedit: error: ...`` line per failed tile on
    stderr; exit code 2 when any tile failed."""
    if getattr(args, "to_splats", False):
        raise ParameterError("--to-splats", "applies to one Gaussian scene, not to a batch of tiles")
    inputs = expand_inputs(args.input)
    ext = args.to or DEFAULT_OUTPUT_EXTENSION
    jobs = plan_jobs(inputs, args.output, ext, overwrite=args.force)
    opts = BatchOptions(remove_outliers=args.remove_outliers, overwrite=args.force,
                        scheduler=args.scheduler or DEFAULT_SCHEDULER, workers=args.workers,
                        halo=not args.independent)
    count = [0]

    def show(r: TileResult) -> None:
        count[0] += 1
        head = f"[{count[0]}/{len(jobs)}]"
        if r.error is not None:
            print(f"splatedit: error: {r.error}", file=sys.stderr, flush=True)
            print(f"{head} failed {r.job.src}", flush=True)
            return
        extra = f", removed {r.removed} outlier(s)" if args.remove_outliers else ""
        notes = "".join(f"; {n}" for n in r.notes)
        print(f"{head} wrote {r.job.out}: {r.written} splats ({r.halo} halo points{extra}, "
              f"{r.seconds:.2f} s){notes}", flush=True)

    t0 = time.perf_counter()
    results = run_batch(jobs, opts, show)
    failed = [r for r in results if r.error is not None]
    print(f"converted {len(results) - len(failed)} of {len(results)} tiles into {args.output} "
          f"in {time.perf_counter() - t0:.2f} s" + (f"; {len(failed)} failed" if failed else ""))
    return 2 if failed else 0

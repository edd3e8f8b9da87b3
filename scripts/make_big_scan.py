"""Generate a synthetic LiDAR-like terrain scan (buildings, trees, noise) as
COPC, streaming in bounded memory (about 3 chunks of 2M points):

    python scripts/make_big_scan.py /work/big/terrain100m.copc.laz --points 100000000 \
        [--laz /work/big/terrain100m.laz] [--seed 0]

See splatedit/bench/terrain.py for the scene.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from splatedit.bench.terrain import write_terrain_copc  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", help="the COPC file to write (.copc.laz)")
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--laz", help="also write the same points as a plain LAZ file here")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    last = [None, 0.0]

    def progress(stage, frac):
        now = time.perf_counter()
        if stage != last[0] or now - last[1] > 5:
            print(f"  {now - t0:7.1f} s  {stage} {100 * frac:5.1f} %", file=sys.stderr, flush=True)
            last[:] = [stage, now]

    rep = write_terrain_copc(a.out, a.points, seed=a.seed, laz_path=a.laz, progress=progress)
    print(f"{rep.path}: {rep.point_count} points, {rep.nodes} nodes, {rep.bytes / 1e6:.1f} MB, "
          f"{time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

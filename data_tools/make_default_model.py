#!/usr/bin/env python3
"""Make splatedit/data/bunny.ply, the embedded default model, from the
Stanford bunny mesh ``bunny00.off`` of the team's sample folder
(../shared/data, from the CGAL 5.5.1 data folder).

The model is written by our own PLY writer with ``axes=False``: double
x y z and the triangle faces, no splat axes.  Reading it derives the vertex
splats from the mesh (splatedit.model.mesh.cloud_from_mesh) exactly as
reading the OFF does, so the result is bit-identical, while the file is less
than half the size of a PLY with stored axes and normals (1.9 MB instead of
4.1 MB) and the faces are kept so an edited mesh can be written back.

Usage: python data_tools/make_default_model.py [--input PATH] [--output PATH]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from splatedit.io import read, write

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--input", type=Path, default=ROOT.parent / "shared" / "data" / "bunny00.off")
    ap.add_argument("--output", type=Path, default=ROOT / "splatedit" / "data" / "bunny.ply")
    args = ap.parse_args(argv)
    src = read(args.input)
    write(args.output, src, overwrite=True, axes=False)
    back = read(args.output)
    for name in ("positions", "u", "v", "faces"):
        if not np.array_equal(getattr(src, name), getattr(back, name)):
            raise SystemExit(f"round trip changed {name}")
    print(f"{args.output}: {back.n} vertices, {len(back.faces)} triangles, "
          f"{args.output.stat().st_size} bytes; splats identical to {args.input.name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

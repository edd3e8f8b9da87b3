#!/usr/bin/env python3
"""Compile shaders_glsl/*.{vert,frag,comp} to SPIR-V.

Single source of truth: ``shaders_glsl/``.  Every stage file ``NAME.STAGE`` is
compiled with exactly::

    glslangValidator -V -Ishaders_glsl -o spirv/NAME.STAGE.spv shaders_glsl/NAME.STAGE

(run from the repository root; ``*.glsl`` files are include-only; a stage file
whose text holds the line ``// spirv: vulkan1.1`` gets ``--target-env vulkan1.1``
appended, for subgroup operations, which need SPIR-V 1.3), and the
result is copied byte for byte to ``splatedit/spirv/`` (package data, what the
renderer loads at run time).  Both copies are committed.

    python data_tools/compile_shaders.py           # compile + copy
    python data_tools/compile_shaders.py --check   # exit 1 if a committed .spv is stale
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SRC = "shaders_glsl"
OUT_DIRS = (ROOT / "spirv", ROOT / "splatedit" / "spirv")
STAGES = (".vert", ".frag", ".comp")
#: a line of a stage file asking for SPIR-V 1.3 (Vulkan 1.1: subgroup operations)
TARGET_VK11 = "// spirv: vulkan1.1"


def shader_sources() -> list[str]:
    """Stage files, relative to the repository root (e.g. ``shaders_glsl/splat.vert``)."""
    return sorted(f"{SRC}/{p.name}" for p in (ROOT / SRC).iterdir() if p.suffix in STAGES)


def compile_one(src: str, out: Path) -> None:
    # glslang 12 wants the include path glued to -I ("-I shaders_glsl" is an
    # error there); includes resolve relative to the including file anyway.
    cmd = ["glslangValidator", "-V", "-I" + SRC, "-o", str(out), src]
    if TARGET_VK11 in (ROOT / src).read_text().splitlines():
        cmd += ["--target-env", "vulkan1.1"]
    try:
        res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    except FileNotFoundError:
        sys.exit("glslangValidator not found (Debian: apt-get install glslang-tools)")
    if res.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{res.stdout}{res.stderr}")


def stale(tmp: Path) -> list[str]:
    """Compile every shader into ``tmp`` and list the committed files that differ."""
    bad = []
    names = []
    for src in shader_sources():
        name = Path(src).name + ".spv"
        names.append(name)
        compile_one(src, tmp / name)
        fresh = (tmp / name).read_bytes()
        for d in OUT_DIRS:
            f = d / name
            if not f.is_file() or f.read_bytes() != fresh:
                bad.append(str(f.relative_to(ROOT)))
    for d in OUT_DIRS:
        if d.is_dir():
            bad += [str(f.relative_to(ROOT)) + " (no source)" for f in d.glob("*.spv") if f.name not in names]
    return bad


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="only check that the committed SPIR-V is fresh")
    args = ap.parse_args(argv)
    if args.check:
        with tempfile.TemporaryDirectory() as tmp:
            bad = stale(Path(tmp))
        if bad:
            print("stale SPIR-V (run python data_tools/compile_shaders.py):\n  " + "\n  ".join(bad))
            return 1
        print("SPIR-V up to date")
        return 0
    for d in OUT_DIRS:
        d.mkdir(parents=True, exist_ok=True)
    for src in shader_sources():
        name = Path(src).name + ".spv"
        compile_one(src, Path("spirv") / name)
        shutil.copyfile(ROOT / "spirv" / name, ROOT / "splatedit" / "spirv" / name)
        print(f"{src} -> spirv/{name}, splatedit/spirv/{name}")
    for d in OUT_DIRS:  # drop outputs whose source is gone
        for f in d.glob("*.spv"):
            if not (ROOT / SRC / f.name[:-4]).is_file():
                f.unlink()
    return 0


if __name__ == "__main__":
    sys.exit(main())

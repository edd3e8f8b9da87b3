"""Data shipped with splatedit: the default model (see PROVENANCE.md)."""

from __future__ import annotations

from pathlib import Path

_HERE = Path(__file__).resolve().parent


def default_model_path() -> Path:
    """Path of the embedded default model, ``bunny.ply`` (the Stanford bunny
    as a triangle mesh; :func:`splatedit.io.read` turns it into vertex splats
    and keeps its faces)."""
    return _HERE / "bunny.ply"


def gaussian_scene_path() -> Path:
    """Path of ``bunny_gaussians.ply``: a 3D Gaussian Splatting test scene of
    5,000 Gaussians with SH degree 3 fitted to the bunny's splats
    (data_tools/make_gaussian_scene.py; see PROVENANCE.md)."""
    return _HERE / "bunny_gaussians.ply"

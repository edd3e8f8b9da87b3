"""The embedded default model."""

from __future__ import annotations

import numpy as np

from splatedit.data import default_model_path
from splatedit.io import read


def test_default_model_reads_as_bunny_mesh_with_outward_splats():
    path = default_model_path()
    assert path.is_file() and path.stat().st_size < 3_000_000
    c = read(path)
    assert c.n == 37706 and len(c.faces) == 75408
    p = c.positions - c.positions.mean(axis=0)
    assert np.mean(np.einsum("ij,ij->i", c.normals, p) > 0) > 0.8


def test_default_model_equals_the_converted_off(shared_data):
    a, b = read(default_model_path()), read(shared_data / "bunny00.off")
    for name in ("positions", "u", "v", "faces"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name

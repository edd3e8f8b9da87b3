"""``read_columns`` stops a read before splats are derived, and
``cloud_from_columns`` of it equals ``read`` (the batch conversion builds on this)."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.io import cloud_from_columns, read, read_columns


@pytest.mark.parametrize("name", ["kitten.xyz", "hippo1.ply", "bunny00.off"])
def test_cloud_from_read_columns_equals_read(shared_data, name):
    path = shared_data / name
    cols = read_columns(path)
    whole = read(path)
    again = cloud_from_columns(cols)
    assert cols.n == whole.n
    np.testing.assert_array_equal(cols.positions, whole.positions)
    np.testing.assert_array_equal(cols.origin, whole.origin)
    for a, b in ((again.u, whole.u), (again.v, whole.v), (again.positions, whole.positions)):
        np.testing.assert_array_equal(a, b)


def test_read_columns_of_a_points_only_file_derives_nothing(tmp_path):
    path = tmp_path / "p.xyz"
    np.savetxt(path, np.random.default_rng(0).random((50, 3)))
    cols = read_columns(path)
    assert cols.needs_estimation() and cols.u is None and cols.normals is None and cols.n == 50

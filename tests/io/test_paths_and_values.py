"""Awkward but legal paths, and values out of a property's range."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.errors import InputError
from splatedit.io import convert, read, write
from splatedit.atomic import atomic_write_text, check_writable_target
from splatedit.model.estimate import estimate_splats


def _cloud():
    rng = np.random.default_rng(0)
    p = rng.normal(size=(300, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    return estimate_splats(p, normals=p, name="été")


def test_non_ascii_file_names_round_trip(tmp_path):
    src = tmp_path / "été.xyz"
    np.savetxt(src, _cloud().positions)
    out = tmp_path / "ünïcode-模型.ply"
    convert(src, out)
    assert read(out).n == 300
    write(tmp_path / "b.ply", _cloud())          # the cloud's name goes into the header comment
    assert read(tmp_path / "b.ply").n == 300


def test_ascii_ply_value_out_of_range_is_an_input_error(tmp_path):
    p = tmp_path / "big.ply"
    p.write_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                 "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                 "end_header\n0 0 0 300 0 0\n")
    with pytest.raises(InputError) as info:
        read(p)
    assert str(p) in str(info.value)


def test_parent_that_is_a_file_is_refused_before_any_work(tmp_path):
    f = tmp_path / "plain.txt"
    f.write_text("x")
    with pytest.raises(InputError, match="is not a directory"):
        check_writable_target(f / "out.ply", overwrite=False)
    with pytest.raises(InputError, match="is not a directory"):
        atomic_write_text(f / "out.json", "{}")
    with pytest.raises(InputError, match="directory does not exist"):
        check_writable_target(tmp_path / "nope" / "out.ply", overwrite=False)

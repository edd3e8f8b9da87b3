"""write/convert never clobber an existing file by accident or by failing."""

from __future__ import annotations

import numpy as np
import pytest

import splatedit.io as sio
from splatedit.errors import InputError
from splatedit.io import convert, read, write


@pytest.fixture
def cloud(tmp_path):
    path = tmp_path / "in.xyz"
    rng = np.random.default_rng(0)
    np.savetxt(path, rng.normal(size=(60, 3)))
    return read(path)


def test_existing_file_is_not_overwritten_without_flag(tmp_path, cloud):
    target = tmp_path / "out.ply"
    target.write_bytes(b"precious")
    with pytest.raises(InputError, match="file exists") as info:
        write(target, cloud)
    assert str(target) in str(info.value)
    assert target.read_bytes() == b"precious"
    write(target, cloud, overwrite=True)
    assert read(target).n == cloud.n


def test_convert_refuses_to_overwrite_its_input(tmp_path, cloud):
    src = write(tmp_path / "a.ply", cloud)
    before = src.read_bytes()
    with pytest.raises(InputError, match="refusing to overwrite the input") as info:
        convert(src, src)
    assert src.name in str(info.value)
    assert src.read_bytes() == before
    assert convert(src, src, overwrite=True).n == cloud.n


def test_failed_write_leaves_old_file_and_no_temp_files(tmp_path, cloud, monkeypatch):
    target = tmp_path / "out.ply"
    target.write_bytes(b"old contents")

    def boom(fh, *a, **k):
        fh.write(b"partial")
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(sio.formats, "write_ply", boom)   # the registry calls it
    with pytest.raises(RuntimeError):
        write(target, cloud, overwrite=True)
    assert target.read_bytes() == b"old contents"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.xyz", "out.ply"]


def test_written_files_get_normal_permissions(tmp_path, cloud):
    import stat
    out = write(tmp_path / "perm.ply", cloud)
    assert stat.S_IMODE(out.stat().st_mode) == 0o644


def test_write_into_missing_directory_is_an_input_error(tmp_path, cloud):
    with pytest.raises(InputError, match="directory does not exist"):
        write(tmp_path / "nope" / "x.ply", cloud)


def test_unknown_output_extension_is_rejected(tmp_path, cloud):
    with pytest.raises(InputError, match="supported"):
        write(tmp_path / "x.obj", cloud)


def test_read_and_write_report_progress(tmp_path, cloud):
    seen = []
    write(tmp_path / "p.ply", cloud, progress=lambda s, f: seen.append((s, f)))
    read(tmp_path / "in.xyz", progress=lambda s, f: seen.append((s, f)))
    stages = {s for s, _ in seen}
    assert {"writing", "reading", "estimating normals", "orienting normals"} <= stages
    assert all(0.0 <= f <= 1.0 for _, f in seen)

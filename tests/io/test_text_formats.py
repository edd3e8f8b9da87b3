"""XYZ and OFF readers: parsing details, colours, polygons, writers."""

from __future__ import annotations

import numpy as np

from splatedit.io import read, write
from splatedit.io._text import scan_numbers


def test_scan_numbers_keeps_line_numbers_across_blocks(monkeypatch):
    import splatedit.io._text as text
    monkeypatch.setattr(text, "TEXT_BLOCK_BYTES", 16)
    data = b"# head\n1 2 3\n\n4 5 6 # tail\n7 8 9\n10 11 12"
    tab = scan_numbers(data, "x")
    assert tab.line.tolist() == [2, 4, 5, 6]
    assert tab.count.tolist() == [3, 3, 3, 3]
    assert tab.values.tolist() == list(range(1, 13))


def test_xyz_with_comments_blank_lines_tabs_and_crlf(tmp_path):
    path = tmp_path / "a.xyz"
    path.write_bytes(b"# x y z\r\n0\t0 0\r\n\r\n1 0 0 # c\r\n0 1 0\r\n1 1 0.5\r\n0.5 0.5 1e-1")
    c = read(path)
    assert c.n == 5 and c.name == "a.xyz" and c.source == str(path)
    assert c.positions[4].tolist() == [0.5, 0.5, 0.1]


def test_xyz_normals_are_taken_from_the_file(tmp_path):
    rng = np.random.default_rng(0)
    p = rng.normal(size=(100, 3))
    n = p / np.linalg.norm(p, axis=1, keepdims=True)
    path = tmp_path / "n.txt"
    np.savetxt(path, np.hstack([p, -n]), fmt="%.17g")
    c = read(path)
    assert np.array_equal(c.positions, p)
    assert np.allclose(c.normals, -n, atol=1e-12)


def test_pts_point_count_header_is_skipped(tmp_path):
    path = tmp_path / "a.pts"
    path.write_bytes(b"4\n0 0 0\n1 0 0\n0 1 0\n1 1 1\n")
    assert read(path).n == 4


def test_off_polygons_are_fan_triangulated_and_comments_allowed(tmp_path):
    path = tmp_path / "q.off"
    path.write_bytes(b"OFF # cube face\n# comment\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n"
                     b"4 0 1 2 3\n3 0 1 4 0.5 0.5 0.5\n")
    c = read(path)
    assert c.faces.tolist() == [[0, 1, 2], [0, 2, 3], [0, 1, 4]]


def test_off_counts_on_keyword_line_and_colours(tmp_path):
    path = tmp_path / "c.off"
    path.write_bytes(b"COFF 3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0\n0 1 0 0 0 255 128\n3 0 1 2\n")
    c = read(path)
    assert c.colors.tolist() == [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 128]]
    assert np.allclose(c.normals, [0, 0, 1])


def test_noff_normals_are_used(tmp_path):
    path = tmp_path / "n.off"
    path.write_bytes(b"NOFF\n3 1 0\n0 0 0 0 0 -1\n1 0 0 0 0 -1\n0 1 0 0 0 -1\n3 0 1 2\n")
    assert np.allclose(read(path).normals, [0, 0, -1])


def test_xyz_and_off_writers_keep_positions_exactly(tmp_path):
    path = tmp_path / "m.off"
    path.write_bytes(b"OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0.3\n0 1 0\n3 0 1 2\n3 0 2 3\n")
    c = read(path)
    off = read(write(tmp_path / "back.off", c))
    assert np.array_equal(off.positions, c.positions) and np.array_equal(off.faces, c.faces)
    xyz = read(write(tmp_path / "back.xyz", c))
    assert np.array_equal(xyz.positions, c.positions)
    assert np.allclose(xyz.normals, c.normals, atol=1e-15)

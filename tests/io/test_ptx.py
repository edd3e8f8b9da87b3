"""Leica PTX reading (splatedit.io.ptx): scans merged in registered
coordinates, missing returns dropped, intensity kept like LAS's, and every
hostile file refused in one line naming the file and the line."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.errors import InputError
from splatedit.io import READ_EXTENSIONS, WRITE_EXTENSIONS, convert, read, write


def _scan(points, transform=np.eye(4), cols=None, rows=None, head=None) -> str:
    """PTX text of one scan: ``points`` (n, 4 or 7) rows, ``transform`` the
    4x4 row-vector matrix (translation in row 4)."""
    n = len(points)
    cols = n if cols is None else cols
    rows = 1 if rows is None else rows
    lines = [str(cols), str(rows), "0 0 0", "1 0 0", "0 1 0", "0 0 1"] if head is None else list(head)
    lines += [" ".join(f"{v:.17g}" for v in r) for r in np.asarray(transform, float)]
    lines += [" ".join(f"{v:.17g}" if j < 4 else f"{int(v)}" for j, v in enumerate(r)) for r in points]
    return "\n".join(lines) + "\n"


def _grid(n_side=8, seed=0):
    """(n, 3) float64 points of a gently bumpy square (a scan needs a surface
    for normal estimation)."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.linspace(0, 1, n_side), np.linspace(0, 1, n_side))
    return np.column_stack([u.ravel(), v.ravel(), 0.02 * rng.random(n_side * n_side)])


def _rotation_z(deg):
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def test_two_scans_are_merged_in_registered_coordinates_without_missing_returns(tmp_path):
    p1, p2 = _grid(seed=1), _grid(seed=2)
    m1 = np.eye(4)
    m2 = np.eye(4)
    m2[:3, :3] = _rotation_z(90.0).T        # row vectors: p @ R.T rotates by R
    m2[3, :3] = [10.0, -5.0, 2.0]
    i1 = np.linspace(0.0, 1.0, len(p1))
    rgb2 = np.tile([[200, 100, 50]], (len(p2), 1))
    s1 = np.column_stack([p1, i1])
    s1[[3, 7]] = [0.0, 0.0, 0.0, 0.5]        # missing returns
    s2 = np.column_stack([p2, np.full(len(p2), 0.25), rgb2])
    s2[0, :3] = 0.0
    path = tmp_path / "two.ptx"
    path.write_text(_scan(s1, m1) + _scan(s2, m2))
    c = read(path)
    keep1 = np.ones(len(p1), bool)
    keep1[[3, 7]] = False
    want = np.vstack([p1[keep1], p2[1:] @ _rotation_z(90.0).T + [10.0, -5.0, 2.0]])
    assert c.n == len(want)
    np.testing.assert_allclose(c.world_positions(), want, atol=1e-9)
    np.testing.assert_array_equal(c.intensity[:keep1.sum()], np.rint(i1[keep1] * 65535).astype(np.uint16))
    assert np.all(c.intensity[keep1.sum():] == round(0.25 * 65535))
    assert np.all(c.colors[keep1.sum():, :3] == [200, 100, 50])


def test_a_scan_without_colours_gets_grey_from_intensity_and_keeps_it_through_las(tmp_path):
    p = _grid()
    inten = np.linspace(0.1, 0.9, len(p))
    path = tmp_path / "grey.PTX"                 # the extension is case-insensitive
    path.write_text(_scan(np.column_stack([p, inten]), cols=8, rows=8))
    c = read(path)
    assert np.all(c.colors[:, 0] == c.colors[:, 1]) and c.colors[:, 0].max() > c.colors[:, 0].min()
    out = convert(path, tmp_path / "grey.las")
    back = read(tmp_path / "grey.las")
    np.testing.assert_array_equal(back.intensity, out.intensity)
    np.testing.assert_array_equal(back.intensity, np.rint(inten * 65535).astype(np.uint16))


def test_ptx_is_read_through_the_registry_and_not_written():
    assert ".ptx" in READ_EXTENSIONS and ".ptx" not in WRITE_EXTENSIONS


def test_writing_ptx_is_refused_with_the_supported_list(tmp_path):
    c = read(_write_small(tmp_path))
    with pytest.raises(InputError, match=r"unsupported file extension '\.ptx' for writing; supported: \.ply"):
        write(tmp_path / "out.ptx", c)


def _write_small(tmp_path):
    path = tmp_path / "small.ptx"
    path.write_text(_scan(np.column_stack([_grid(), np.full(64, 0.5)])))
    return path


_IDENTITY = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"
_HEAD = "2\n1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"

#: (file text, the message's words, the 1-based line it names or None)
HOSTILE = [
    ("", "empty file", None),
    ("# only a comment\n", "empty file", None),
    ("2\n1\n0 0 0\n1 0 0\n", "scan 1: the header is cut short (4 of its 10 lines)", 1),
    ("2\n1\n0 0\n1 0 0\n0 1 0\n0 0 1\n" + _IDENTITY + "1 2 3 0.5\n4 5 6 0.5\n",
     "scan 1 header: expected 3 numbers (the scanner position), got 2", 3),
    ("2.5\n1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n" + _IDENTITY + "1 2 3 0.5\n4 5 6 0.5\n",
     "the column count 2.5 is not an integer", 1),
    ("-2\n1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n" + _IDENTITY + "1 2 3 0.5\n",
     "the column count -2 is not an integer", 1),
    (_HEAD + "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 nan 1\n" + "1 2 3 0.5\n4 5 6 0.5\n",
     "transform row 4 is not finite", 10),
    (_HEAD + "1 0 0 5\n0 1 0 0\n0 0 1 0\n0 0 0 1\n" + "1 2 3 0.5\n4 5 6 0.5\n",
     "the transform's last column is 5 0 0 1, not 0 0 0 1", 7),
    (_HEAD + _IDENTITY + "1 2 3 0.5\n", "the header says 2 x 1 = 2 points but only 1 line follow", 1),
    (_HEAD + _IDENTITY + "1 2 3\n4 5 6\n", "expected 4 or 7 columns (x y z intensity [r g b]), got 3", 11),
    (_HEAD + _IDENTITY + "1 2 3 0.5\n4 5 6 0.5 9\n", "wrong column count: expected 4 like line 11, got 5", 12),
    (_HEAD + _IDENTITY + "1 2 3 0.5\n4 5 inf 0.5\n", "value is infinite", 12),
    (_HEAD + _IDENTITY + "1 2 3 0.5\n4 5 6 1.5\n", "intensity 1.5 is not in 0..1", 12),
    (_HEAD + _IDENTITY + "1 2 3 0.5 1 2 3\n4 5 6 0.5 1 2 300\n", "300", 12),
    (_HEAD + _IDENTITY + "1 2 x 0.5\n4 5 6 0.5\n", "not a number: 'x'", 11),
    (_HEAD + _IDENTITY + "0 0 0 0.5\n0 0 0 0.5\n", "no points: 1 scan, every point a missing return", None),
    (_HEAD + _IDENTITY + "1 2 3 0.5\n4 5 6 0.5\n" + "1\n", "scan 2: the header is cut short", 13),
]


@pytest.mark.parametrize("text,words,line", HOSTILE, ids=[h[1][:40] for h in HOSTILE])
def test_hostile_ptx_is_one_line_naming_the_file_and_line(tmp_path, text, words, line):
    path = tmp_path / "bad.ptx"
    path.write_text(text)
    with pytest.raises(InputError) as got:
        read(path)
    msg = str(got.value)
    assert "\n" not in msg and str(path) in msg and words in msg, msg
    if line is not None:
        assert f"line {line}" in msg, msg

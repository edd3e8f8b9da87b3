"""Scanner formats through the commands: convert between them, info, and a
georeferenced scan renders like the same scan near 0."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

from splatedit.io import read, write
from splatedit.model.cloud import SplatCloud


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "splatedit.cli", "-q", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def _utm_sphere(n=3000, centre=(512_345.0, 5_123_456.0, 300.0), r=20.0):
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5 ** 0.5) * i
    nrm = np.column_stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z])
    a = np.where(np.abs(nrm[:, [0]]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    t1 = np.cross(nrm, a)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(nrm, t1)
    s = r * np.sqrt(4 * np.pi / n)
    world = np.round(r * nrm + np.asarray(centre), 3)
    return world, t1 * s, t2 * s


def test_convert_las_to_ply_to_laz_to_pcd_keeps_millimetres_and_intensity(tmp_path):
    import laspy
    world, u, v = _utm_sphere()
    origin = np.array([512_345.0, 5_123_456.0, 300.0])
    cloud = SplatCloud(world - origin, u, v, origin=origin,
                       intensity=np.arange(len(world)) % 4000, classification=np.full(len(world), 6))
    write(tmp_path / "a.las", cloud)
    steps = ["a.las", "b.ply", "c.laz", "d.pcd", "e.las"]
    for src, dst in zip(steps, steps[1:]):
        res = run_cli("convert", tmp_path / src, tmp_path / dst)
        assert res.returncode == 0, res.stderr
    a, e = laspy.read(str(tmp_path / "a.las")), laspy.read(str(tmp_path / "e.las"))
    # the same millimetres (the PCD step carries no origin: e.las may have another offset)
    for j, d in enumerate("XYZ"):
        mm_a = np.asarray(a[d], dtype=np.int64) + round(a.header.offsets[j] / 0.001)
        mm_e = np.asarray(e[d], dtype=np.int64) + round(e.header.offsets[j] / 0.001)
        assert np.array_equal(mm_a, mm_e), d
    assert np.array_equal(laspy.read(str(tmp_path / "c.laz")).intensity, a.intensity)


def test_info_of_a_utm_las_prints_its_origin_and_local_bounds(tmp_path):
    world, u, v = _utm_sphere()
    origin = np.array([512_345.0, 5_123_456.0, 300.0])
    write(tmp_path / "a.laz", SplatCloud(world - origin, u, v, origin=origin))
    res = run_cli("info", tmp_path / "a.laz", "--json")
    assert res.returncode == 0, res.stderr
    info = json.loads(res.stdout)
    assert info["origin"][1] > 5e6 and max(abs(x) for x in info["bounds_max"]) < 100


def test_bad_scanner_files_are_one_line_errors(tmp_path):
    (tmp_path / "x.pcd").write_bytes(b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                                     b"COUNT 1 1 1\nPOINTS 2\nDATA ascii\n0 0 0\n1 2\n")
    (tmp_path / "y.las").write_bytes(b"LASF garbage")
    for name in ("x.pcd", "y.las"):
        res = run_cli("info", tmp_path / name)
        assert res.returncode == 2 and res.stderr.count("\n") == 1, res.stderr
        assert res.stderr.startswith("splatedit: error: ") and name in res.stderr


def test_georeferenced_scan_renders_like_the_same_scan_near_zero(tmp_path):
    from PIL import Image
    world, u, v = _utm_sphere()
    far = tmp_path / "far.ply"
    near = tmp_path / "near.ply"
    write(far, SplatCloud(world - world.mean(0).round(), u, v, origin=world.mean(0).round()))
    write(near, SplatCloud(world - world.mean(0).round(), u, v))
    assert read(far).origin.any()
    imgs = []
    for src in (far, near):
        png = tmp_path / (src.stem + ".png")
        res = run_cli("render", src, "-o", png, "--size", "96x96")
        assert res.returncode == 0, res.stderr
        imgs.append(np.asarray(Image.open(png)).astype(int))
    cover = [(im[..., 3] > 0).mean() if im.shape[-1] == 4 else (im.sum(-1) > 0).mean() for im in imgs]
    assert cover[1] > 0.2
    assert np.abs(imgs[0] - imgs[1]).max() <= 2

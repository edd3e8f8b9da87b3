"""``splatedit convert`` over a folder or a glob of tiles on Dask
(splatedit.commands.batch): one output per tile named after it, seams that
match the merged cloud, a broken tile reported by name with the rest kept,
and the same results on a distributed cluster as on the local pool
(the process pool, 10-20 s of start-up on the loaded test machine, is run
by ``splatedit bench batch``)."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

import splatedit.tolerances
from splatedit.bench.batch import seam_check, terrain_tiles
from splatedit.cli import main
from splatedit.io.batch import BatchOptions, load_tile, plan_jobs, run_batch
from splatedit.io import read


@pytest.fixture(scope="module")
def tiles(tmp_path_factory):
    """2 x 2 terrain tiles of ~1500 points each (.xyz: positions only, so
    every tile needs normals and sizes) and all their points."""
    folder = tmp_path_factory.mktemp("tiles")
    paths, merged = terrain_tiles(folder, 2, 2, 1500, ext=".xyz", seed=3)
    return folder, paths, merged


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_folder_batch_writes_one_output_per_tile_named_after_it_and_keeps_the_inputs(tiles, tmp_path, capsys):
    folder, paths, _ = tiles
    before = {p: _digest(p) for p in paths}
    out = tmp_path / "out"
    assert main(["-q", "convert", str(folder), str(out), "--workers", "2"]) == 0
    text = capsys.readouterr().out
    assert sorted(p.name for p in out.iterdir()) == sorted(p.stem + ".ply" for p in paths)
    for p in paths:
        assert f"wrote {out / (p.stem + '.ply')}" in text
        assert read(out / (p.stem + ".ply")).n == len(np.loadtxt(p))
        assert _digest(p) == before[p]
    assert f"converted {len(paths)} of {len(paths)} tiles" in text


def test_glob_batch_takes_only_the_matching_tiles_in_the_format_asked(tiles, tmp_path, capsys):
    folder, paths, _ = tiles
    out = tmp_path / "out"
    assert main(["-q", "convert", str(folder / "tile_*_0.xyz"), str(out), "--to", ".laz"]) == 0
    want = sorted(p.stem + ".laz" for p in paths if p.stem.endswith("_0"))
    assert sorted(p.name for p in out.iterdir()) == want and len(want) == 2


def test_seam_normals_and_sizes_equal_those_of_the_merged_cloud(tiles, tmp_path, monkeypatch):
    """With the halo the splats of points near inner tile borders equal those
    of estimating the merged cloud at once; without it (halo 0, the plain
    per-file loop) they do not, so the check can fail."""
    _, paths, merged = tiles
    border = 2.0 * load_tile(str(paths[0])).reach

    def seams(halo: float, name: str) -> dict:
        monkeypatch.setattr(splatedit.tolerances, "TILE_HALO_NEIGHBOURHOODS", halo)
        jobs = plan_jobs(paths, tmp_path / name, ".ply", overwrite=False)
        assert all(r.error is None for r in run_batch(jobs, BatchOptions(workers=2)))
        return seam_check([j.out for j in jobs], merged, border=border)

    with_halo = seams(splatedit.tolerances.TILE_HALO_NEIGHBOURHOODS, "halo")
    assert with_halo["seam_points"] > 200 and with_halo["match_dist_max"] < 1e-9
    assert with_halo["normal_deg_max"] < 1e-4          # float64 rounding (arccos near 1)
    assert with_halo["normal_flipped_frac"] == 0.0
    assert with_halo["radius_rel_max"] < 1e-9
    without = seams(0.0, "none")
    assert without["normal_deg_max"] > 1.0 or without["radius_rel_max"] > 0.01


def test_broken_tile_is_reported_by_name_and_the_rest_are_written(tiles, tmp_path, capsys):
    folder, paths, _ = tiles
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    for p in paths:
        (mixed / p.name).write_bytes(p.read_bytes())
    bad = mixed / "broken.xyz"
    bad.write_text("1 2 3\n4 five 6\n")
    out = tmp_path / "out"
    assert main(["-q", "convert", str(mixed), str(out)]) == 2
    cap = capsys.readouterr()
    errors = [ln for ln in cap.err.splitlines() if ln.startswith("splatedit: error:")]
    assert len(errors) == 1 and str(bad) in errors[0], cap.err
    assert sorted(p.name for p in out.iterdir()) == sorted(p.stem + ".ply" for p in paths)
    assert f"converted {len(paths)} of {len(paths) + 1} tiles" in cap.out and "1 failed" in cap.out


def test_batch_refuses_to_write_over_inputs_or_existing_outputs_before_any_work(tiles, tmp_path, capsys):
    folder, paths, _ = tiles
    assert main(["-q", "convert", str(folder), str(folder), "--to", ".xyz"]) == 2
    assert "is one of the inputs" in capsys.readouterr().err
    out = tmp_path / "out"
    out.mkdir()
    (out / (paths[1].stem + ".ply")).write_text("old")
    assert main(["-q", "convert", str(folder), str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("splatedit: error:") and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in out.iterdir()) == [paths[1].stem + ".ply"]   # nothing else written


def test_scheduler_address_runs_the_batch_on_a_distributed_cluster(tiles, tmp_path, capsys):
    distributed = pytest.importorskip("distributed", reason="the distributed package is not installed")
    folder, paths, _ = tiles
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        out = tmp_path / "out"
        assert main(["-q", "convert", str(folder), str(out), "--scheduler", cluster.scheduler_address]) == 0
    local = tmp_path / "local"
    assert main(["-q", "convert", str(folder), str(local)]) == 0
    capsys.readouterr()
    for p in paths:
        name = p.stem + ".ply"
        assert _digest(out / name) == _digest(local / name)


def test_remove_outliers_drops_a_far_stray_of_one_tile_and_keeps_the_rest(tiles, tmp_path, capsys):
    folder, paths, _ = tiles
    src = tmp_path / "in"
    src.mkdir()
    for p in paths:
        (src / p.name).write_bytes(p.read_bytes())
    stray = np.array([[50.0, 50.0, 400.0]])
    with open(src / paths[0].name, "a") as fh:
        np.savetxt(fh, stray, fmt="%.4f")
    out = tmp_path / "out"
    assert main(["-q", "convert", str(src), str(out), "--remove-outliers"]) == 0
    cloud = read(out / (paths[0].stem + ".ply"))
    assert (cloud.positions + cloud.origin)[:, 2].max() < 100.0
    assert "removed" in capsys.readouterr().out


def test_independent_files_are_converted_each_alone_without_a_halo(tiles, tmp_path, capsys):
    """--independent: separate models, no halo; each output equals ``convert FILE OUT``."""
    folder, paths, _ = tiles
    out = tmp_path / "out"
    assert main(["-q", "convert", str(folder), str(out), "--independent"]) == 0
    assert "(0 halo points" in capsys.readouterr().out
    alone = tmp_path / "alone.ply"
    assert main(["-q", "convert", str(paths[0]), str(alone)]) == 0
    np.testing.assert_array_equal(read(out / (paths[0].stem + ".ply")).u, read(alone).u)


def test_ply_tiles_of_laz_tiles_say_they_are_z_up(tmp_path, capsys):
    """LAZ tiles are Z-up by their format: their PLY copies name +Z in the
    header, so each opens (and renders) standing as the tile did."""
    from splatedit.model.orientation import header_up_hint
    folder = tmp_path / "laz"
    folder.mkdir()
    paths, _ = terrain_tiles(folder, 2, 1, 800, ext=".laz", seed=5)
    out = tmp_path / "out"
    assert main(["-q", "convert", str(folder), str(out), "--workers", "1"]) == 0
    capsys.readouterr()
    for p in paths:
        hint = header_up_hint(out / (p.stem + ".ply"))
        assert hint is not None and hint.label == "+Z", p

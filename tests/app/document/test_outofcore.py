"""The out-of-core document (splatedit.app.document.outofcore) without a window: the
shown nodes are real points of the file, appending keeps every index, the
selection spreads to a loaded region, moved points are found by node and row,
and a session waiting for its region neither fits nor moves."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.app.document.outofcore import adopt_appended, open_scan
from splatedit.app.document.session import Session
from splatedit.select.selection import HANDLE
from tests.app.copc_scans import terrain_copc

pytest.importorskip("lazrs", reason="COPC point data is LAZ-compressed (lazrs)")


@pytest.fixture(scope="module")
def scan_file(tmp_path_factory):
    return terrain_copc(tmp_path_factory.mktemp("copc") / "terrain.copc.laz")


def file_points(scan, t):
    block = scan.copc.read([scan.by_tuple[t]])
    return block.xyz[np.argsort(block.row)]


def test_open_scan_shows_the_octree_top_as_points_of_the_file(scan_file):
    scan, cloud = open_scan(scan_file, lambda *a: None, first=5000, budget=20_000)
    assert [t for t, _, _ in scan.segments] == [(0, 0, 0, 0)]
    assert cloud.n == scan.copc.nodes[scan.by_tuple[(0, 0, 0, 0)]].point_count < 5000
    np.testing.assert_array_equal(cloud.positions + scan.origin, file_points(scan, (0, 0, 0, 0)))
    assert cloud.colors is not None and (cloud.radii > 0).all()


def test_extend_keeps_indices_and_shrinks_only_covered_splats(scan_file):
    scan, cloud = open_scan(scan_file, lambda *a: None, first=5000, budget=20_000)
    kids = [t for t in scan.by_tuple if t[0] == 1]
    nodes = dict(scan.nodes)
    nodes.update(scan.read(kids))
    grown, segs = scan.extend(cloud, scan.segments, kids, nodes)
    n0 = cloud.n
    np.testing.assert_array_equal(grown.positions[:n0], cloud.positions)
    assert grown.n == n0 + sum(nodes[t].n for t in kids)
    for t, start, count in segs:
        np.testing.assert_allclose(grown.positions[start:start + count] + scan.origin, file_points(scan, t),
                                   rtol=0, atol=1e-9)
    # finer nodes shown: the root's splats never grow and some shrink
    r0, r1 = cloud.radii, grown.radii[:n0]
    assert (r1 <= r0 * (1 + 1e-12)).all() and (r1 < r0 * 0.99).any()


def test_adopt_appended_spreads_the_support_to_the_nearby_new_points(scan_file):
    scan, cloud = open_scan(scan_file, lambda *a: None, first=5000, budget=20_000)
    s = Session(cloud, fit_sync=True)
    centre = np.array([50.0, 60.0, 0.0]) + scan_file_origin_offset(scan)
    near = np.linalg.norm(cloud.positions[:, :2] - centre[:2], axis=1) < 20.0   # ~4 root spacings
    s.paint(np.flatnonzero(near))
    s.end_stroke(True)
    kids = [t for t in scan.by_tuple if t[0] == 1]
    nodes = dict(scan.nodes)
    nodes.update(scan.read(kids))
    grown, _ = scan.extend(cloud, scan.segments, kids, nodes)
    adopt_appended(s, grown, label="full resolution")
    sup = s.selection.support
    assert s.cloud is grown and len(sup) == grown.n
    np.testing.assert_array_equal(sup[:cloud.n], near)
    d_new = np.linalg.norm(grown.positions[cloud.n:, :2] - centre[:2], axis=1)
    new_sup = sup[cloud.n:]
    assert new_sup[d_new < 14.0].all()              # inside the painted disc: taken
    assert not new_sup[d_new > 26.0].any()          # beyond a root spacing outside: not
    assert s.history.labels[s.history.position] == "full resolution"
    assert s.undo() and s.cloud is cloud            # one undo step back to the shown level


def scan_file_origin_offset(scan):
    """Local coordinates of the terrain's corner (the file's terrain starts at TERRAIN_ORIGIN)."""
    from tests.app.copc_scans import TERRAIN_ORIGIN
    return TERRAIN_ORIGIN - scan.origin


def test_moved_nodes_reports_exactly_the_moved_rows(scan_file):
    scan, cloud = open_scan(scan_file, lambda *a: None, first=20_000, budget=20_000)
    pos = cloud.positions.copy()
    t, start, count = scan.segments[1]
    pos[start + 3] += [0.0, 0.0, 1.5]
    pos[start + 7] += [0.25, 0.0, 0.0]
    moved = scan.moved_nodes(cloud.replace(positions=pos))
    assert list(moved) == [t]
    rows, xyz = moved[t]
    assert rows.tolist() == [3, 7]
    want = file_points(scan, t)[[3, 7]] + [[0.0, 0.0, 1.5], [0.25, 0.0, 0.0]]
    np.testing.assert_allclose(xyz, want, rtol=0, atol=1e-9)


def test_a_waiting_session_neither_fits_nor_moves_and_keeps_its_splats(scan_file):
    from tests.app.sessions import view
    scan, cloud = open_scan(scan_file, lambda *a: None, first=5000, budget=20_000)
    s = Session(cloud, fit_sync=True)
    s.splats_fixed = "kept in the file"
    order = np.argsort(np.linalg.norm(cloud.positions[:, :2] - cloud.positions[0, :2], axis=1))
    s.paint(order[:300])            # a disc of the root's points and its centre as the handle
    s.end_stroke(True)
    assert s.remove_splats() == 0 and s.cloud.n == cloud.n
    s.waiting = "loading"
    s.brush_target = HANDLE
    s.paint(order[:20])
    s.end_stroke(True)
    s.request_fit()
    assert s.basis is None and s.state == "waiting"
    assert not s.begin("grab", view(), (100.0, 100.0))
    s.waiting = None
    s.request_fit()
    assert s.wait_fit() and s.fit_error is None and s.basis is not None and s.begin("grab", view(), (100.0, 100.0))


def test_a_support_too_large_for_full_resolution_waits_until_it_shrinks(scan_file, monkeypatch):
    import types

    from splatedit.app.document import outofcore
    monkeypatch.setattr(outofcore, "EDITOR_OOC_REGION_MAX_POINTS", 1000)
    scan, cloud = open_scan(scan_file, lambda *a: None, first=5000, budget=20_000)
    s = Session(cloud, fit_sync=True)
    said = []
    ed = types.SimpleNamespace(session=s, jobs={}, say=said.append, wake=lambda: None)
    s.end_stroke(s.paint(np.arange(cloud.n)))          # everything: the whole file's nodes are missing
    box = scan.region_needed(s)
    assert box is not None
    scan.start_region(ed, box)
    assert not ed.jobs and s.waiting and "paint a smaller support" in said[-1]
    assert s.state == "waiting" and s.stats().error == s.waiting
    s.clear()
    assert scan.region_needed(s) is None and s.waiting is None


def test_a_large_non_copc_scan_opens_through_its_copc_cache(tmp_path, monkeypatch):
    import laspy

    from splatedit import tolerances
    from splatedit.app.document.outofcore import is_out_of_core
    from tests.app.copc_scans import terrain_points
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    xyz, _ = terrain_points(20_000, seed=3)
    las = laspy.create(point_format=6, file_version="1.4")
    las.header.scales = [0.001] * 3
    las.header.offsets = np.round(xyz.min(0))
    las.x, las.y, las.z = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    path = tmp_path / "tile.las"
    las.write(path)
    assert not is_out_of_core(path)
    monkeypatch.setattr(tolerances, "EDITOR_OOC_CONVERT_BYTES", path.stat().st_size - 1)
    assert is_out_of_core(path)
    stages = []
    scan, cloud = open_scan(path, lambda st, f: stages.append(st), first=5000, budget=20_000)
    assert scan.path == path and scan.source != path and (tmp_path / "cache") in scan.source.parents
    assert "converting to a COPC cache (once)" in stages and scan.copc.point_count == 20_000
    from scipy.spatial import cKDTree
    d, _ = cKDTree(xyz).query(cloud.positions + scan.origin)
    assert d.max() < 1e-3 and cloud.n == 20_000    # the scan on its 0.001 grid (one 20k leaf node: the root)


def test_file_indices_point_at_the_same_points_in_the_file_read_whole(scan_file):
    from splatedit.io import read
    scan, cloud = open_scan(scan_file, lambda *a: None, first=5000, budget=20_000)
    kids = [t for t in scan.by_tuple if t[0] == 1][:3]
    nodes = dict(scan.nodes)
    nodes.update(scan.read(kids))
    grown, scan.segments = scan.extend(cloud, scan.segments, kids, nodes)
    whole = read(str(scan_file))
    idx = scan.file_indices(grown.n)
    assert len(np.unique(idx)) == grown.n
    np.testing.assert_allclose(whole.world_positions(idx), grown.positions + scan.origin, rtol=0, atol=1e-6)


def _loop_editor(s):
    """What OutOfCoreScan.poll and landed touch of the editor: no window, no levels of detail."""
    import types
    return types.SimpleNamespace(session=s, jobs={}, say=lambda *a: None, wake=lambda: None, size=(640, 480),
                                 cam=types.SimpleNamespace(state=lambda: (0,)), viewport=types.SimpleNamespace(
                                     set_pyramid=lambda p: None), frames=types.SimpleNamespace(invalidate=lambda: None),
                                 drag=types.SimpleNamespace(name="NONE"), use_lod=False)


def _painted_disc(scan, cloud):
    s = Session(cloud, fit_sync=True)
    centre = np.array([50.0, 60.0, 0.0]) + scan_file_origin_offset(scan)
    s.end_stroke(s.paint(np.flatnonzero(np.linalg.norm(cloud.positions[:, :2] - centre[:2], axis=1) < 20.0)))
    return s


def test_a_stroke_painted_while_the_view_refines_stops_the_refinement_and_loads_its_region(scan_file):
    import time

    from splatedit.app.document.jobs import Cancelled, Job
    from splatedit.app.document.outofcore import REGION_JOB, VIEW_JOB
    scan, cloud = open_scan(scan_file, lambda *a: None, first=5000, budget=20_000)
    ed = _loop_editor(Session(cloud, fit_sync=True))

    def refining(progress):          # a view refinement that runs until it is cancelled
        while True:
            progress("reading the view's nodes", 0.0)
            time.sleep(0.01)
    view = ed.jobs[VIEW_JOB] = Job("refining the view", refining)
    scan.poll(ed)
    assert ed.jobs == {VIEW_JOB: view}              # no selection: the refinement goes on
    ed.session = s = _painted_disc(scan, cloud)
    scan.poll(ed)
    assert VIEW_JOB not in ed.jobs and REGION_JOB in ed.jobs     # the region at once, not after the view
    assert view.wait(10.0) and isinstance(view.error, Cancelled)
    region = ed.jobs.pop(REGION_JOB)
    assert region.wait(60.0) and region.error is None
    scan.landed(ed, REGION_JOB, region.result)
    assert s.cloud.n > cloud.n and s.waiting is None and scan.region_needed(s) is None


def test_a_refinement_landing_under_a_painted_support_lets_its_region_load_next(scan_file):
    from splatedit.app.document.outofcore import VIEW_JOB
    scan, cloud = open_scan(scan_file, lambda *a: None, first=5000, budget=20_000)
    s = _painted_disc(scan, cloud)
    ed = _loop_editor(s)
    lo, hi, missing = scan.region_box(s)
    assert len(missing) >= 2
    nodes = dict(scan.nodes)
    nodes.update(scan.read(missing[:1]))            # a view job that brought one of the region's nodes
    result = ("append",) + scan.extend(cloud, scan.segments, missing[:1], nodes) + (nodes, cloud)
    scan.landed(ed, VIEW_JOB, result)
    assert s.cloud.n > cloud.n
    box = scan.region_needed(s)                     # checked on the grown cloud's version, not skipped
    assert box is not None and missing[0] not in box[2] and set(missing[1:]) <= set(box[2])

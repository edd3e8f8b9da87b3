"""The editor's background neighbour graph: one progress bar that rises, a
note for the brush while it runs, and a cancel that stops the build within a
tile or two (quitting, opening another model) instead of running it out."""

from __future__ import annotations

import functools
import time

import pytest

import splatedit.select.graph as graph_mod
from splatedit.app.document import selection as seltools
from splatedit.bench.editor import bunny_surface_cloud
from splatedit.app.document.jobs import Cancelled, Job
from splatedit.model.tiles import tiled_knn
from splatedit.select.graph import NeighbourGraph


@pytest.fixture
def cloud(monkeypatch):
    # 200k splats in tiles of 4,000 points: ~50 tiles, a build of ~1-2 s
    monkeypatch.setattr(graph_mod, "tiled_knn", functools.partial(tiled_knn, tile_points=4000))
    return bunny_surface_cloud(200_000)


def _tools():
    return seltools.SelectionTools(lambda name, fn: Job(name, fn))


def test_the_graph_job_reports_one_rising_bar_and_the_graph_arrives(cloud):
    tools = _tools()
    seen = []
    tools.prepare(cloud)
    job = tools._job
    while not job.done:
        f = tools.building(cloud)
        if f is not None:
            seen.append((job.stage, f))
        time.sleep(0.01)
    assert tools.poll() and tools.building(cloud) is None
    assert tools.graph(cloud, wait=False) is not None
    fractions = [f for _, f in seen]
    assert {stage for stage, _ in seen} == {seltools.GRAPH_JOB_STAGE}
    assert fractions == sorted(fractions)                 # never goes back
    assert len(set(fractions)) >= 3                       # moves while the tiles run


def test_cancel_stops_the_build_at_the_next_tile(cloud):
    t0 = time.perf_counter()
    NeighbourGraph.build(cloud.positions).warm()
    full_s = time.perf_counter() - t0
    tools = _tools()
    tools.prepare(cloud)
    job = tools._job
    while job.fraction <= 0.05 and not job.done:           # inside the tiles' k-NN
        time.sleep(0.005)
    t0 = time.perf_counter()
    tools.cancel()
    assert job.wait(30)
    stop_s = time.perf_counter() - t0
    assert isinstance(job.error, Cancelled)
    assert stop_s < 0.25 * full_s, (stop_s, full_s)
    assert not tools.poll() and tools.graph(cloud, wait=False) is None

"""Splat sizes of rotating-sensor scans (lidar and scanning radar, xyz only):
no splat much larger than the splats around it, and no hole for it.

The scans come from data_tools/make_radar_scan.py (ray cast scenes with
multipath ghosts, near-sensor dust, far returns, poles and wires, quantised
to millimetres in float32)."""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest
from scipy.spatial import cKDTree

import splatedit.model.estimate as estimate
from splatedit.io import read
from splatedit.model.estimate import estimate_splats
from splatedit.model.sizing import settle_radii
from splatedit.tolerances import SIZE_CAP_REL_NEIGHBOURS, SIZE_NEIGHBOURS
from tests.conftest import REPO_ROOT
from tests.model.scan_helpers import uncovered


@pytest.fixture(scope="module")
def scans():
    """The data_tools/make_radar_scan.py module."""
    name = "make_radar_scan"
    spec = importlib.util.spec_from_file_location(name, REPO_ROOT / "data_tools" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod              # its dataclass looks its module up
    try:
        spec.loader.exec_module(mod)
    finally:
        del sys.modules[name]
    return mod


def _origins(sweeps):
    return [(6.0 * i, 0.0, 1.8) for i in range(sweeps)]


def neighbour_ratio(points, radii, k: int = SIZE_NEIGHBOURS - 1) -> np.ndarray:
    """(n,) every radius over the median radius of its k nearest other points."""
    _, nb = cKDTree(points).query(points, k=k + 1)
    return radii / np.median(radii[nb[:, 1:]], axis=1)


def _unsettled(monkeypatch, points):
    with monkeypatch.context() as m:
        m.setattr(estimate, "settle_radii", lambda r, nb, changed, **kw: r)
        return estimate_splats(points)


CAP = SIZE_CAP_REL_NEIGHBOURS * (1 + 1e-9)


@pytest.mark.parametrize("kind, seed, sweeps, before", [("lidar", 0, 1, 7.32), ("radar", 1, 2, 5.55)])
def test_rotating_scan_splats_stay_within_the_cap_of_their_neighbours(scans, monkeypatch, kind, seed,
                                                                      sweeps, before):
    """The largest splat over the median of its 15 nearest neighbours' was
    7.3x (lidar, 42k points) and 5.6x (radar, two sweeps, 9k) when only the
    spacing rule's radii were capped (ghosts and dust next to flagged
    outliers whose discs the outlier cap had shrunk); all splats now stay
    within SIZE_CAP_REL_NEIGHBOURS (3x; the goal of issue 23 is 4x)."""
    p = scans.rotating_scan(kind, seed, _origins(sweeps))
    old = neighbour_ratio(p, _unsettled(monkeypatch, p).radii)
    assert old.max() == pytest.approx(before, rel=0.02)
    q = neighbour_ratio(p, estimate_splats(p).radii)
    assert q.max() <= CAP, f"largest splat {q.max():.2f}x its neighbours' median"


def test_real_lidar_scan_splats_stay_within_the_cap_of_their_neighbours(shared_data, monkeypatch):
    """poste_france.xyz: 6.05x (20 splats above 4x) before, at most 3x now."""
    p = read(shared_data / "poste_france.xyz").positions
    assert neighbour_ratio(p, _unsettled(monkeypatch, p).radii).max() > 4.0
    assert neighbour_ratio(p, estimate_splats(p).radii).max() <= CAP


def test_settling_opens_no_hole_in_the_scanned_surfaces(scans, monkeypatch):
    """Probes of the radar scene's surfaces twice as dense as its beams: the
    same probes are covered with and without settling (it only shrinks
    ghosts, dust and stray returns: 9 of 8,924 splats here)."""
    origins = _origins(2)
    p = scans.rotating_scan("radar", 1, origins)
    probes = scans.surface_probes("radar", 1, origins, fine=2)
    before, after = _unsettled(monkeypatch, p), estimate_splats(p)
    shrunk = after.radii < before.radii * (1 - 1e-12)
    assert 0 < shrunk.sum() <= 0.002 * len(p)
    assert uncovered(after, probes) == uncovered(before, probes)


def test_generated_scans_look_like_a_rotating_sensors(scans):
    """Spacing grows with range (and is anisotropic far away), every kind of
    outlier is there, coordinates are float32 values of a millimetre grid."""
    p, lab = scans.rotating_scan("radar", 0, labels=True)
    assert set(np.unique(lab)) == {scans.SURFACE, scans.GHOST, scans.FAR, scans.DUST}
    assert np.array_equal(p, p.astype(np.float32).astype(np.float64))
    assert np.abs(p * 1000 - np.round(p * 1000)).max() < 0.01
    s = p[lab == scans.SURFACE]
    rng_xy = np.linalg.norm(s[:, :2], axis=1)
    d, _ = cKDTree(s).query(s, k=2)
    near, far = rng_xy < 10, rng_xy > 30
    assert np.median(d[far, 1]) > 3 * np.median(d[near, 1])


def test_settle_radii_caps_against_the_shrunk_neighbours():
    """A splat (index 0) whose four neighbours the outlier cap shrank from 4 to
    1 is capped at 3x their new median; the others keep their sizes."""
    r = np.array([4.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    nb = np.array([[1, 2, 3, 4], [0, 2, 3, 5], [0, 1, 3, 5], [0, 1, 2, 5], [0, 1, 2, 5], [1, 2, 3, 4]])
    changed = np.array([False, True, True, True, True, False])
    out = settle_radii(r, nb, changed, cap=3.0)
    np.testing.assert_array_equal(out, [3.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    assert np.array_equal(settle_radii(r, nb, np.zeros(6, bool), cap=3.0), r)

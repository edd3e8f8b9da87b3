"""Statistical and isolated outlier detection on real scans with injected strays."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from splatedit.io import read
from splatedit.model.outliers import detect_outliers
from tests.model.scan_helpers import SCANS, inject_outliers, spacing


@pytest.mark.parametrize("name", SCANS)
def test_injected_outliers_are_found_with_high_recall_and_precision(shared_data, name):
    """1 % uniform outliers in the bounding box plus 5 far strays: recall over
    the injected points more than 5 spacings off the scan, precision over all
    flags (points the clean file already flags, e.g. poste_france's own
    strays, count for neither)."""
    p = read(shared_data / name).positions
    n = len(p)
    own = detect_outliers(p).mask
    q = inject_outliers(p)
    flags = detect_outliers(q).mask
    off = cKDTree(p).query(q[n:])[0] > 5 * spacing(p)
    recall = flags[n:][off].mean()
    false_pos = int((flags[:n] & ~own).sum())
    precision = flags[n:].sum() / (flags[n:].sum() + false_pos)
    assert off.sum() >= 30
    assert recall >= 0.8, f"recall {recall:.2f} of {off.sum()}"
    assert precision >= 0.95, f"precision {precision:.2f} ({false_pos} scan points flagged)"
    assert flags[-5:].all(), "a far stray was missed"


@pytest.mark.parametrize("name", ["kitten.xyz", "hippo1.ply", "bunny00.off"])
def test_clean_scans_flag_almost_nothing(shared_data, name):
    p = read(shared_data / name).positions
    flags = detect_outliers(p)
    assert flags.count <= 0.002 * len(p), f"{flags.count} of {len(p)} flagged"
    assert not flags.isolated.any()


def test_a_point_far_above_a_plane_is_isolated_and_statistical():
    rng = np.random.default_rng(0)
    plane = np.column_stack([rng.random((4000, 2)), np.zeros(4000)])
    h = spacing(plane)
    pts = np.vstack([plane, [[0.5, 0.5, 20 * h]]])
    flags = detect_outliers(pts)
    assert flags.isolated[-1] and flags.statistical[-1]
    assert flags.count == 1
    assert 10 * h * 0.9 < flags.isolation_radius < 10 * h * 1.1


def test_sparser_region_is_not_an_outlier():
    """A region sampled 3x sparser (a scan's far side) stays inside the
    distribution: the test is taken of log distances."""
    rng = np.random.default_rng(1)
    dense = np.column_stack([rng.random((9000, 2)), np.zeros(9000)])
    sparse = np.column_stack([rng.random((1000, 2)) + [1.0, 0.0], np.zeros(1000)])
    flags = detect_outliers(np.vstack([dense, sparse]))
    assert flags.count <= 5


def test_tiny_and_degenerate_inputs_flag_nothing():
    for pts in (np.zeros((1, 3)), np.eye(3)[:2], np.zeros((10, 3))):
        flags = detect_outliers(pts)
        assert flags.count == 0 and flags.mask.shape == (len(pts),)


def test_small_far_clusters_are_strays_and_the_main_piece_is_not():
    """A sampled sphere with three far clumps of 10 points: exactly the clumps."""
    from splatedit.model.outliers import detect_outliers, stray_clusters
    rng = np.random.default_rng(3)
    s = rng.normal(size=(5000, 3))
    s /= np.linalg.norm(s, axis=1, keepdims=True)
    clumps = [c + 0.02 * rng.normal(size=(10, 3)) for c in ([30.0, 0, 0], [0, -40.0, 5], [8, 8, 60])]
    pts = np.vstack([s] + clumps)
    flags = detect_outliers(pts)
    strays = stray_clusters(pts, flags.isolation_radius)
    assert strays[5000:].all() and not strays[:5000].any()


def test_remove_outliers_frames_the_lidar_scan(shared_data, tmp_path):
    """poste_france.xyz: its far clumps of 8-28 points set a 258-unit bounding
    box around a 21-unit object; --remove-outliers drops them."""
    import subprocess
    import sys
    out = tmp_path / "poste.ply"
    r = subprocess.run([sys.executable, "-m", "splatedit.cli", "-q", "convert", str(shared_data / "poste_france.xyz"),
                        str(out), "--remove-outliers"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "in small far clusters" in r.stdout
    from splatedit.io import read
    assert read(out).diagonal < 30.0

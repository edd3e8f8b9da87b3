"""Octree node selection (splatedit.model.octree_lod): refinement toward the
camera, the point budget, parents before children, the frustum."""

import math
from dataclasses import dataclass

import numpy as np

from splatedit.model.octree_lod import OctreeView, children_of, select_nodes
from splatedit.render.camera import perspective


@dataclass
class Node:
    point_count: int
    bounds: np.ndarray


def full_octree(depth: int, count: int = 100, size: float = 8.0) -> dict:
    """Every node of a complete octree over [0, size]^3 down to ``depth``."""
    nodes = {}
    for d in range(depth + 1):
        n = 2 ** d
        w = size / n
        for x in range(n):
            for y in range(n):
                for z in range(n):
                    lo = np.array([x, y, z], float) * w
                    nodes[(d, x, y, z)] = Node(count, np.stack([lo, lo + w]))
    return nodes


def look_at(eye, target, up):
    """(4, 4) world -> camera matrix looking from ``eye`` at ``target`` (camera looks along -z)."""
    back = eye - target
    back /= np.linalg.norm(back)
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = right, np.cross(back, right), back
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def view_from(eye, target, h=400, fov=60.0, far=100.0):
    vp = perspective(fov, 1.0, 0.01, far) @ look_at(np.asarray(eye, float), np.asarray(target, float),
                                                     np.array([0.0, 0.0, 1.0]))
    return OctreeView(np.asarray(eye, float), vp, math.radians(fov), h)


def test_select_nodes_refines_toward_the_camera():
    nodes = full_octree(4)
    view = view_from([-2.0, 4.0, 4.0], [8.0, 4.0, 4.0])     # looking along +x from the x=0 side
    got = select_nodes(nodes, 1.0, view, budget=20_000)
    deep = [k for k in got.keys if k[0] >= 3]
    assert deep, "some nodes refined to depth 3+"
    x_mean = np.mean([(k[1] + 0.5) / 2 ** k[0] for k in deep])
    # the deep nodes sit on the near half (x < 4 of 8)
    assert x_mean < 0.5
    near = [k for k in got.keys if k[0] == 4 and k[1] == 0]
    far = [k for k in got.keys if k[0] == 4 and k[1] == 15]
    assert len(near) > len(far)


def test_select_nodes_respects_the_budget_and_stops_refining_in_the_distance():
    nodes = full_octree(4)
    view = view_from([-2.0, 4.0, 4.0], [8.0, 4.0, 4.0])
    for budget in (100, 1000, 5000, 30_000):
        got = select_nodes(nodes, 1.0, view, budget=budget)
        assert got.points <= max(budget, 100)
        assert got.points == 100 * len(got.keys)
    small = select_nodes(nodes, 1.0, view, budget=1000)
    assert not small.complete
    # far away, the root's spacing is below a pixel: only the root
    far = select_nodes(nodes, 1.0, view_from([-5000.0, 4.0, 4.0], [8.0, 4.0, 4.0]), budget=10**9)
    assert far.keys == ((0, 0, 0, 0),) and far.complete


def test_select_nodes_orders_parents_before_children_coarse_to_fine():
    nodes = full_octree(4)
    got = select_nodes(nodes, 1.0, view_from([-2.0, 4.0, 4.0], [8.0, 4.0, 4.0]), budget=50_000)
    pos = {k: i for i, k in enumerate(got.keys)}
    for k in got.keys:
        if k[0] > 0:
            parent = (k[0] - 1, k[1] // 2, k[2] // 2, k[3] // 2)
            assert parent in pos and pos[parent] < pos[k], k
    assert got.keys[0] == (0, 0, 0, 0)
    # the first node of each depth is not deeper than the nodes before it allow
    depths = [k[0] for k in got.keys]
    assert depths.index(1) < depths.index(2) < depths.index(3)


def test_select_nodes_does_not_refine_outside_the_frustum():
    nodes = full_octree(3)
    # inside the box at x = 6 looking along +x: the nodes behind the eye (x < 4) stay coarse
    got = select_nodes(nodes, 1.0, view_from([5.0, 4.0, 4.0], [8.0, 4.0, 4.0], fov=40.0), budget=10**9)
    deep = [k for k in got.keys if k[0] == 3]
    assert deep and all(k[1] >= 4 for k in deep)


def test_select_nodes_keeps_the_always_nodes_and_counts_them():
    nodes = full_octree(3)
    view = view_from([-2.0, 4.0, 4.0], [8.0, 4.0, 4.0])
    region = [k for k in children_of((2, 3, 3, 3))]
    got = select_nodes(nodes, 1.0, view, budget=2000, always=region)
    assert set(region) <= set(got.keys)
    assert got.points <= 2000
    assert got.points == 100 * len(got.keys)

"""Vertex splats of triangle meshes."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.errors import InputError
from splatedit.model.mesh import cloud_from_mesh
from splatedit.tolerances import MESH_SPLAT_RADIUS_FACTOR


def uv_sphere(n_lat=24, n_lon=48):
    """Closed UV sphere, counter-clockwise seen from outside."""
    th = np.linspace(0, np.pi, n_lat + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, n_lon, endpoint=False)
    T, P = np.meshgrid(th, ph, indexing="ij")
    ring = np.column_stack([(np.sin(T) * np.cos(P)).ravel(), (np.sin(T) * np.sin(P)).ravel(),
                            np.cos(T).ravel()])
    verts = np.vstack([[0, 0, 1.0], ring, [0, 0, -1.0]])
    faces = []
    idx = lambda i, j: 1 + i * n_lon + (j % n_lon)
    for j in range(n_lon):
        faces.append([0, idx(0, j), idx(0, j + 1)])
        faces.append([len(verts) - 1, idx(n_lat - 2, j + 1), idx(n_lat - 2, j)])
    for i in range(n_lat - 2):
        for j in range(n_lon):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            faces += [[a, b, c], [a, c, d]]
    return verts, np.asarray(faces)


def test_mesh_normals_match_sphere_analytic_normals():
    v, f = uv_sphere()
    c = cloud_from_mesh(v, f)
    cos = np.einsum("ij,ij->i", c.normals, v)
    assert np.degrees(np.arccos(np.clip(cos.min(), -1, 1))) < 2.0
    assert np.array_equal(c.faces, f)


def test_mesh_splats_cover_every_triangle():
    """Every point of every triangle projects into the disc of one of its corners."""
    v, f = uv_sphere(12, 20)
    c = cloud_from_mesh(v, f)
    rng = np.random.default_rng(0)
    r1, r2 = np.sqrt(rng.random((len(f), 200))), rng.random((len(f), 200))
    w = np.stack([1 - r1, r1 * (1 - r2), r1 * r2], -1)              # (f, s, 3)
    x = np.einsum("fsk,fkd->fsd", w, v[f])
    covered = np.zeros(x.shape[:2], dtype=bool)
    for k in range(3):
        i = f[:, k]
        d = x - v[i][:, None, :]
        rr = np.linalg.norm(c.u[i], axis=1)[:, None] ** 2
        s = np.einsum("fsd,fd->fs", d, c.u[i]) / rr
        t = np.einsum("fsd,fd->fs", d, c.v[i]) / rr
        covered |= s * s + t * t <= 1.0
    assert covered.all()


def test_mesh_radius_is_factor_times_longest_incident_edge():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 2, 0], [5, 5, 5.0]])
    c = cloud_from_mesh(v, np.array([[0, 1, 2]]))
    assert np.allclose(c.radii[:3], MESH_SPLAT_RADIUS_FACTOR * np.sqrt(5))
    assert np.allclose(c.normals[:3], [0, 0, 1])
    assert c.radii[3] > 0          # isolated vertex: spacing-based


def test_isolated_vertices_get_pca_normals_oriented_with_neighbours():
    v, f = uv_sphere()
    extra = np.array([[0.0, 0.0, 1.0], [1.0, 0, 0]]) * 1.0001
    c = cloud_from_mesh(np.vstack([v, extra]), f)
    n = c.normals[-2:]
    assert np.all(np.einsum("ij,ij->i", n, extra) > 0.95)


def test_face_index_out_of_range_names_face_row():
    with pytest.raises(InputError, match="row 1"):
        cloud_from_mesh(np.eye(3), np.array([[0, 1, 2], [0, 1, 3]]))

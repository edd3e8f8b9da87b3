"""Chunked orientation (splatedit.model.orient) against the whole-cloud pass."""

from __future__ import annotations

import numpy as np

from splatedit.model.estimate import estimate_normals, knn
from splatedit.model.orient import orient_normals
from splatedit.model.pca import morton_order


def test_chunked_orientation_is_outward_and_equals_the_single_chunk_result():
    """Two spheres, Morton-sorted, cut into chunks of 700 points (pieces end
    at every chunk border, the MST joins them): every normal outward, the
    same signs as one chunk over the whole cloud."""
    rng = np.random.default_rng(5)
    a = rng.normal(size=(4000, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = rng.normal(size=(3000, 3))
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    outward = np.vstack([a, b])
    p = np.vstack([a, 2.0 * b + [6.0, 0.0, 0.0]])
    o = morton_order(p)
    p, outward = p[o], outward[o]
    _, nb = knn(p, 17)
    nrm = estimate_normals(p, neighbours=nb) * rng.choice([-1.0, 1.0], size=(len(p), 1))
    whole = orient_normals(p, nrm, neighbours=nb, chunk=len(p))
    chunked = orient_normals(p, nrm, neighbours=nb, chunk=700)
    assert np.all(np.einsum("ij,ij->i", chunked, outward) > 0)
    assert np.array_equal(chunked, whole)

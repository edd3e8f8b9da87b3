"""Helpers that write PLY variants with plyfile (an independent writer)."""

from __future__ import annotations

import numpy as np
import plyfile


def make_ply(path, positions, *, text=False, byte_order="<", fdtype="f4", normals=None,
             colors=None, color_dtype="u1", radius=None, axes=None, faces=None, extra=None):
    fields = [(p, fdtype) for p in "xyz"]
    if normals is not None:
        fields += [(p, fdtype) for p in ("nx", "ny", "nz")]
    if radius is not None:
        fields.append(("radius", fdtype))
    if axes is not None:
        fields += [(p, fdtype) for p in ("ux", "uy", "uz", "vx", "vy", "vz")]
    if colors is not None:
        fields += [(p, color_dtype) for p in ("red", "green", "blue", "alpha")[:colors.shape[1]]]
    if extra:
        fields += [(k, v.dtype.str) for k, v in extra.items()]
    arr = np.empty(len(positions), dtype=fields)
    for j, p in enumerate("xyz"):
        arr[p] = positions[:, j]
    if normals is not None:
        for j, p in enumerate(("nx", "ny", "nz")):
            arr[p] = normals[:, j]
    if radius is not None:
        arr["radius"] = radius
    if axes is not None:
        for j, p in enumerate(("ux", "uy", "uz", "vx", "vy", "vz")):
            arr[p] = axes[:, j]
    if colors is not None:
        for j, p in enumerate(("red", "green", "blue", "alpha")[:colors.shape[1]]):
            arr[p] = colors[:, j]
    for k, v in (extra or {}).items():
        arr[k] = v
    elements = [plyfile.PlyElement.describe(arr, "vertex")]
    if faces is not None:
        fa = np.empty(len(faces), dtype=[("vertex_indices", object)])
        fa["vertex_indices"] = [np.asarray(f, dtype=np.int32) for f in faces]
        elements.append(plyfile.PlyElement.describe(fa, "face"))
    plyfile.PlyData(elements, text=text, byte_order=byte_order).write(str(path))
    return path


def grid_mesh(nx=6, ny=5):
    """A wavy height-field quad mesh: (n, 3) vertices and quads as lists."""
    x, y = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny))
    z = 0.1 * np.sin(3 * x) * np.cos(2 * y)
    verts = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    quads = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a = j * nx + i
            quads.append([a, a + 1, a + nx + 1, a + nx])
    return verts, quads

"""``splatedit deform`` and ``splatedit render`` of COPC files out of core
(:mod:`splatedit.io.copc`): only the octree nodes an edit's regions or the
camera need are read.

Deform: the nodes whose cubes meet the script's regions (every support and
delete region, grown by a margin, see :func:`edit_region`) are read at full
resolution into a splat cloud with the whole file's local origin, the script
runs on it as in memory (:func:`splatedit.script.run_script`), and
:func:`splatedit.io.copc.rewrite_copc` writes the file again, re-encoding the
nodes with changed points and copying every other node's compressed bytes.

Render: the nodes are chosen for the camera as Potree does
(:func:`choose_nodes`): a node's children are read while its point spacing
projects to more than ``COPC_REFINE_PX`` pixels, nearest first, within a
point budget; then the normal splat renderer.
"""

from __future__ import annotations

import heapq
import sys
import time

import numpy as np

from splatedit.errors import EditScriptError, ParameterError


def is_copc_path(path) -> bool:
    """True for a ``.copc.laz`` name or a file whose first VLR is COPC info."""
    from splatedit.io.copc import is_copc
    from splatedit.io.formats import suffix_of
    return suffix_of(path) == ".copc.laz" or is_copc(path)


def _region_box(region, source: str, jp: str) -> np.ndarray:
    """(2, 3) local-coordinate box of a script region (sphere or box)."""
    from splatedit.select.regions import Box, Sphere
    if isinstance(region, Sphere):
        c = np.asarray(region.center, float)
        return np.stack([c - region.radius, c + region.radius])
    if isinstance(region, Box):
        return np.stack([np.asarray(region.min, float), np.asarray(region.max, float)])
    raise EditScriptError("an index list selects splats of the whole model; out of core (a COPC file) "
                          "regions must be spheres or boxes", json_path=jp, path=source)


def edit_region(script, source: str) -> np.ndarray:
    """(2, 3) the local box around every support and delete region of
    ``script``, grown on each side by ``COPC_EDIT_MARGIN_REL`` of its
    longest side (the fit's border ring and the neighbours that size and
    orient the splats at the support's rim lie there).

    Raises:
        EditScriptError: an index-list region or a crop (they concern the
        whole model).
    """
    from splatedit.script.model import Removal
    from splatedit.tolerances import COPC_EDIT_MARGIN_REL
    boxes = []
    for item in script.edits:
        if isinstance(item, Removal):
            if item.keep:
                raise EditScriptError("crop keeps one region of the whole model; out of core (a COPC file) "
                                      "use delete", json_path=item.json_path, path=source)
            boxes.append(_region_box(item.region, source, f"{item.json_path}.{item.key}"))
        else:
            boxes.append(_region_box(item.support, source, f"{item.json_path}.support"))
            for k, h in enumerate(item.handles):
                boxes.append(_region_box(h, source, f"{item.json_path}.handles[{k}]"))
    lo = np.min([b[0] for b in boxes], axis=0)
    hi = np.max([b[1] for b in boxes], axis=0)
    m = COPC_EDIT_MARGIN_REL * float(np.max(hi - lo))
    return np.stack([lo - m, hi + m])


def deform_copc(args, print_edit) -> int:
    """``splatedit deform IN.copc.laz SCRIPT -o OUT.copc.laz`` out of core."""
    from splatedit.io.copc import CopcFile, cloud_of_block, file_origin, rewrite_copc
    from splatedit.script import load_script, run_script
    t0 = time.perf_counter()
    script = load_script(args.edit)
    source = str(args.edit)
    box = edit_region(script, source)
    src = CopcFile.open(args.input)
    try:
        origin = file_origin(src)
        nodes = src.select(box + origin)
        if not nodes:
            raise EditScriptError("the script's regions lie outside the model", json_path="$", path=source)
        block = src.read(nodes, args.progress)
        cloud = cloud_of_block(src, block, args.progress)
        out, reports = run_script(cloud, script, method=args.method, tol=args.tol, source=source,
                                  progress=args.progress, on_edit=print_edit)
        rows = out.point_fields["copc_block_row"]
        changed = np.any(out.positions != cloud.positions[rows], axis=1)
        keep = np.zeros(len(block), bool)
        keep[rows] = True
        new_xyz = block.xyz.copy()
        new_xyz[rows[changed]] = out.positions[changed] + origin
        dirty = np.zeros(len(block), bool)
        dirty[rows[changed]] = True
        dirty |= ~keep
        starts = {k: s for k, s in zip(block.keys, np.searchsorted(block.node, np.arange(len(block.keys))))}
        touched = [block.keys[i] for i in np.unique(block.node[dirty])]

        def edit(node, nb):
            s = starts[node.key]
            g = s + nb.row.astype(np.int64)
            if not dirty[g].any():
                return None
            nb.xyz = new_xyz[g]
            return nb.take(keep[g])

        rep = rewrite_copc(src, args.output, edit, args.progress, only=touched)
    finally:
        src.close()
    args.progress.close()
    print(f"wrote {args.output}: {rep.point_count} points, {len(reports)} edit(s) on {len(block)} points "
          f"read from {len(nodes)} of {len(src.nodes)} nodes; {rep.encoded} node(s) re-encoded, {rep.created} "
          f"created, {rep.copied} copied, {rep.moved} point(s) changed node, {time.perf_counter() - t0:.2f} s")
    return 0


# --------------------------------------------------------------------------- render


def choose_nodes(src, camera, size, *, budget: int, refine_px: float):
    """The nodes to draw for ``camera`` (an image of ``size`` (w, h)), as
    Potree chooses them: from the root, a node in front of the camera and
    inside its view cone is drawn, and its children visited while its point
    spacing (``src.spacing / 2**depth``) projects to more than ``refine_px``
    pixels at the node's nearest point; the largest projected spacing first,
    until ``budget`` points.

    Returns:
        list of NodeKey (parents before children).
    """
    from splatedit.io.copc import ROOT
    eye = np.asarray(camera.eye, float)
    fwd = np.asarray(camera.target, float) - eye
    fwd /= np.linalg.norm(fwd)
    focal = 0.5 * size[1] / np.tan(np.radians(camera.fov_deg) / 2)
    half_diag = np.hypot(size[0], size[1]) / 2 / focal          # tan of the cone's half angle
    cone = np.arctan(half_diag)

    def weight(key):
        b = src.node_bounds(key)
        near = np.clip(eye, b[0], b[1])
        dist = float(np.linalg.norm(near - eye))
        centre = b.mean(axis=0)
        radius = float(np.linalg.norm(b[1] - b[0])) / 2
        to = centre - eye
        d = float(np.linalg.norm(to))
        if d > radius:       # outside the view cone (cone widened by the node's bounding sphere)
            ang = np.arccos(np.clip(to @ fwd / d, -1, 1))
            if ang - np.arcsin(min(1.0, radius / d)) > cone:
                return None
        spacing = src.spacing / (1 << key.depth)
        return spacing * focal / max(dist, 1e-12)

    out, total = [], 0
    w = weight(ROOT)
    heap = [(-w, ROOT)] if ROOT in src.nodes and w is not None else []
    structure = src._structure if hasattr(src, "_structure") else set()
    while heap:
        negw, key = heapq.heappop(heap)
        n = src.nodes.get(key)
        if n is not None:
            if total + n.point_count > budget and out:
                break
            out.append(key)
            total += n.point_count
        if -negw <= refine_px:
            continue
        for c in key.children():
            if c in src.nodes or c in structure:
                cw = weight(c)
                if cw is not None:
                    heapq.heappush(heap, (-cw, c))
    return out

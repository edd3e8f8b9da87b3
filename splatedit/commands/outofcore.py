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
(:func:`splatedit.io.copc.choose_nodes`): a node's children are read while its point spacing
projects to more than ``COPC_REFINE_PX`` pixels, nearest first, within a
point budget; then the normal splat renderer.
"""

from __future__ import annotations

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


def _index_regions(script) -> list:
    """The index-list regions of ``script`` (support, handles, delete regions)."""
    from splatedit.select.regions import Indices
    out = []
    for item in script.edits:
        regions = [item.region] if hasattr(item, "region") else [item.support, *item.handles]
        out += [r for r in regions if isinstance(r, Indices)]
    return out


def file_order(src):
    """(keys in file order, (m,) int64 index of each node's first point in the
    file read whole): points are numbered node by node in chunk order, each
    node's rows in order, as :func:`splatedit.io.read` reads a COPC file."""
    nodes = sorted(src.nodes.values(), key=lambda n: n.offset)
    counts = np.array([n.point_count for n in nodes], dtype=np.int64)
    return [n.key for n in nodes], np.cumsum(counts) - counts


def indexed_box(src, script, origin) -> np.ndarray | None:
    """(2, 3) local box around the points an index-list script names (whole-file
    indices, as the editor writes them for a scan opened out of core), grown by
    ``COPC_EDIT_MARGIN_REL`` like :func:`edit_region`; None without index lists."""
    from splatedit.tolerances import COPC_EDIT_MARGIN_REL
    regions = _index_regions(script)
    if not regions:
        return None
    idx = np.unique(np.concatenate([np.asarray(r.indices, dtype=np.int64) for r in regions]))
    keys, first = file_order(src)
    if len(idx) and (idx[0] < 0 or idx[-1] >= src.point_count):
        raise EditScriptError(f"an index list names point {int(idx[-1] if idx[-1] >= 0 else idx[0])} of a "
                              f"{src.point_count}-point file", json_path="$", path=str(src.path))
    at = np.searchsorted(first, idx, side="right") - 1
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for j in np.unique(at):
        block = src.read([keys[j]])
        rows = idx[at == j] - first[j]
        pts = block.xyz[np.argsort(block.row)][rows] - origin
        lo, hi = np.minimum(lo, pts.min(0)), np.maximum(hi, pts.max(0))
    m = COPC_EDIT_MARGIN_REL * float(np.max(hi - lo))
    return np.stack([lo - m, hi + m])


def localize_indices(src, script, block):
    """``script`` with its whole-file index lists turned into indices of
    ``block``'s points (in block order); every named point must be in it."""
    import dataclasses

    from splatedit.select.regions import Indices
    keys, first = file_order(src)
    pos = {k: i for i, k in enumerate(keys)}
    glob = np.array([first[pos[k]] for k in block.keys], dtype=np.int64)[block.node] + block.row
    order = np.argsort(glob, kind="stable")
    sorted_glob = glob[order]

    def region(r):
        if not isinstance(r, Indices):
            return r
        idx = np.asarray(r.indices, dtype=np.int64)
        at = np.searchsorted(sorted_glob, idx)
        ok = (at < len(sorted_glob)) & (sorted_glob[np.minimum(at, len(sorted_glob) - 1)] == idx)
        if not ok.all():
            raise EditScriptError("an index list names points outside the region read", json_path="$",
                                  path=str(src.path))
        return Indices(tuple(int(i) for i in np.sort(order[at])))
    items = []
    for e in script.edits:
        if hasattr(e, "region"):
            e = dataclasses.replace(e, region=region(e.region))
        else:
            e = dataclasses.replace(e, support=region(e.support), handles=tuple(region(h) for h in e.handles))
        items.append(e)
    return dataclasses.replace(script, edits=tuple(items))


def deform_copc(args, print_edit) -> int:
    """``splatedit deform IN.copc.laz SCRIPT -o OUT.copc.laz`` out of core."""
    from splatedit.io.copc import CopcFile, cloud_of_block, file_origin, rewrite_copc
    from splatedit.script import load_script, run_script
    t0 = time.perf_counter()
    script = load_script(args.edit)
    source = str(args.edit)
    src = CopcFile.open(args.input)
    try:
        origin = file_origin(src)
        # an index-list script (the editor's, for a scan opened out of core) names
        # points of the whole file: its box comes from those points
        box = indexed_box(src, script, origin)
        box = edit_region(script, source) if box is None else box
        nodes = src.select(box + origin)
        if not nodes:
            raise EditScriptError("the script's regions lie outside the model", json_path="$", path=source)
        block = src.read(nodes, args.progress)
        if _index_regions(script):
            script = localize_indices(src, script, block)
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


def render_copc(args, camera_from_args) -> int:
    """``splatedit render IN.copc.laz -o x.png`` out of core: the camera from
    the root node's points (the default view of the whole model, or the
    flags), then the nodes of :func:`choose_nodes` read into one cloud and
    drawn by the splat renderer (``--edl`` available)."""
    from splatedit.io.copc import ROOT, CopcFile, choose_nodes, cloud_of_block, file_origin
    from splatedit.render.splat.headless import render_to_png
    from splatedit.tolerances import COPC_REFINE_PX, COPC_RENDER_BUDGET
    if args.edit is not None:
        raise ParameterError("--edit", "a COPC file is rendered out of core without an edit: apply the script "
                                       "with 'splatedit deform' (out of core too) and render the result")
    if args.buffers is not None:
        raise ParameterError("--buffers", "is not available for a COPC file rendered out of core")
    t0 = time.perf_counter()
    src = CopcFile.open(args.input)
    try:
        origin = file_origin(src)
        top = [ROOT] if ROOT in src.nodes else [n.key for n in src.select(max_depth=1)]
        coarse = cloud_of_block(src, src.read(top))
        camera = camera_from_args(args, coarse)
        budget = getattr(args, "budget", None) or COPC_RENDER_BUDGET
        lo, hi = np.asarray(src.point_bounds, dtype=np.float64) - origin
        near, far = camera.clip_range(lo, hi)
        to_local = np.eye(4)
        to_local[:3, 3] = -origin                  # file units -> the camera's local frame
        vp = camera.projection_matrix(args.size[0] / args.size[1], near, far) @ camera.view_matrix() @ to_local
        keys = choose_nodes(src, np.asarray(camera.eye) + origin, vp, camera.fov_deg, args.size,
                            budget=budget, refine_px=COPC_REFINE_PX)
        keys = keys or top          # nothing in view: the frame shows what the coarse points show (nothing)
        block = src.read(keys, args.progress)
        cloud = cloud_of_block(src, block, args.progress)
    finally:
        src.close()
    drawn, path = cloud, getattr(args, "path", None)
    if not getattr(args, "full", False):      # as for any model: a level about a pixel wide where splats crowd
        from splatedit.render.splat.headless import drawn_for_view
        drawn, path = drawn_for_view(cloud, camera, args.size[1], path)
    render_to_png(drawn, args.output, size=args.size, camera=camera, raster_path=path,
                  edl=getattr(args, "edl", False))
    args.progress.close()
    depth = max((k.depth for k in keys), default=0)
    print(f"wrote {args.output} ({args.size[0]}x{args.size[1]}, {cloud.n} of {src.point_count} points from "
          f"{len(keys)} of {len(src.nodes)} nodes, levels 0..{depth}, out of core, "
          f"{time.perf_counter() - t0:.2f} s)")
    return 0

"""JSON edit scripts: parse, validate and run a sequence of RBF edits headlessly.

Format (version 1)::

    {"version": 1,
     "solver": {"method": "auto"|"iqr"|"lu", "tol": 1e-7, "max_centers": null},
     "edits": [
       {"support": REGION,
        "handle": REGION,                    # or "handles": [REGION, ...]
        "transform": TRANSFORM,              # or "transforms": [TRANSFORM, ...]
        "curves": [CURVE, ...],              # optional; see below
        "deformation": "rotation"},          # optional: "rotation" (default) | "linear" | "detail"
       {"delete": REGION},                   # removes the splats of REGION
       {"crop": REGION}]}                    # keeps only the splats of REGION

    REGION    = {"sphere": {"center": [x,y,z], "radius": r}}      (a support region may add
                                                                "fill_holes": false)
              | {"box": {"min": [x,y,z], "max": [x,y,z]}}
              | {"indices": [i, ...]}
    TRANSFORM = {"matrix": [[4 numbers] x 4]}                      (row-major, acts on column vectors)
              | {"translate": [dx,dy,dz],
                 "rotate": {"axis": [ax,ay,az], "degrees": a, "center": [x,y,z]},
                 "scale": s | {"factor": s, "center": [x,y,z]}}     (any subset)

    CURVE     = {"points": [[x,y,z], ...],      (k + 1 >= 2 picked points, consecutive ones distinct)
                 "move": [[dx,dy,dz], ...],      (one displacement per picked point)
                 "samples": n}                   (optional integer >= 2; default: one per point spacing)

An edit needs at least one handle or curve: exactly one of ``handle`` /
``handles`` (with ``transform`` / ``transforms``), and/or ``curves``.  A curve
is the centripetal Catmull-Rom curve through its ``points`` (no overshoot; a
segment through 2; see splatedit.deform.curves); the edit moves the *picked
points* by ``move`` and every curve sample by a non-negative, smooth blend of
the moves of the two picked points around it, so the moved curve passes
through ``points + move`` and no part of it moves against the drags.  The curve need not lie on the surface; only its samples
over the free part of the support constrain the edit.  Curves take the
column blocks after the handles.

``delete`` and ``crop`` items remove splats (a scan's stray points, a
floor): the model after them has fewer splats, renumbered in order, and the
``indices`` of later items count in it.  A delete or crop that would leave
no splat is an error (its JSON path), as is one that selects none.

A handle region is intersected with its support.  A TRS transform applies
scale, then rotation, then translation; the rotation and scale centres default
to the handle's centroid.  Edits run one after another: each edit's result is
the base of the next (the paper's Bunny: ears, then head).  Every error names
the JSON path of the bad value, e.g. ``$.edits[0].transform.rotate.axis`` or
``$.edits[1].curves[0].move[2]``.

``deformation`` picks how the handles' maps spread over the support
(:class:`~splatedit.deform.modes.DeformationMode`): ``"rotation"`` (the
default) blends each handle's rotation over the support, so bends and twists
of 90 degrees and more keep their cross-sections; ``"linear"`` is the paper's
deformation (exact for translations, large rotations shrink the middle);
``"detail"`` splits the support into a smooth base surface plus normal
offsets, deforms the base rotation-aware and re-attaches the offsets along
the deformed normals (relief keeps its height and stays upright; see
:mod:`splatedit.deform.detail`).  Curves are displacements in every mode.

The package: :mod:`splatedit.script.model` (the dataclasses and the JSON
output), :mod:`splatedit.script.parse` (reading and validation) and
:mod:`splatedit.script.run` (running edits, reports); everything is
exported here.
"""

from splatedit.script.model import (METHODS, SCRIPT_VERSION, TRS, Curve, Edit, EditScript, Matrix,
                                    Removal, SolverSettings, Transform)
from splatedit.script.parse import decode_json, load_script, parse_script, read_limited
from splatedit.script.run import (EditReport, RemovalReport, ResolvedEdit, fit_edit, remove_splats,
                                  removal_mask, resolve_edit, resolve_edit_inputs, run_script)

__all__ = ["METHODS", "SCRIPT_VERSION", "TRS", "Curve", "Edit", "EditScript", "Matrix", "Removal", "SolverSettings",
           "Transform", "decode_json", "load_script", "parse_script", "read_limited", "EditReport",
           "RemovalReport", "ResolvedEdit", "fit_edit", "remove_splats", "removal_mask", "resolve_edit", "resolve_edit_inputs", "run_script"]

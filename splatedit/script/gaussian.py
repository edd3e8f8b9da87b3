"""Running JSON edit scripts (:mod:`splatedit.script`) on Gaussian splatting scenes.

Regions select Gaussian *centres*; each edit's basis is fitted on the scene's
proxy splats (:meth:`GaussianCloud.proxy_splats`: centres plus the two largest
axes), so the selection closure, bands and solver work unchanged.  The edit
moves the centres by ``B dC`` and transports each Gaussian's covariance and
spherical harmonics with the Jacobian (:mod:`splatedit.deform.gaussians`).
Edits run one after another, each on the previous result.
"""

from __future__ import annotations

import time
from typing import Callable

import numpy as np

from splatedit.deform.distortion import distortion_from_axes
from splatedit.deform.gaussians import deform_with_evaluator
from splatedit.deform.modes import DeformationMode
from splatedit.errors import EditScriptError, InputError
from splatedit.model.gaussians import GaussianCloud
from splatedit.script import EditReport, EditScript, Removal, RemovalReport, fit_edit, removal_mask


def run_script_gaussians(scene: GaussianCloud, script: EditScript, *, method: str | None = None,
                         tol: float | None = None, source: str | None = None, progress=None,
                         on_edit: Callable[[EditReport], None] | None = None):
    """Apply every edit of ``script`` to a Gaussian scene in order.

    Returns:
        (deformed GaussianCloud, list of EditReport)
    Raises:
        EditScriptError: bad regions, a failed fit, or an edit that flattens
            Gaussians (JSON path of the edit).
    """
    reports = []
    for i, edit in enumerate(script.edits):
        if isinstance(edit, Removal):       # delete / crop: the Gaussians left, in order
            kept = removal_mask(scene.positions, edit, source)
            scene = scene.take(kept)
            rep = RemovalReport(i, edit.key, int((~kept).sum()), int(kept.sum()))
            reports.append(rep)
            if on_edit is not None:
                on_edit(rep)
            continue
        if edit.deformation is DeformationMode.DETAIL:
            # the detail mode's offsets along a smoothed base are defined for surface splats only
            raise EditScriptError("the detail mode is not available for Gaussian splatting scenes "
                                  "(use \"rotation\" or \"linear\")",
                                  json_path=f"{edit.json_path}.deformation", path=source)
        proxy = scene.proxy_splats()
        r, basis, d_c = fit_edit(proxy, edit, script.solver, method=method, tol=tol,
                                 source=source, progress=progress)
        t0 = time.perf_counter()
        try:
            new = deform_with_evaluator(scene, basis, d_c)
        except InputError as exc:
            raise EditScriptError(f"the edit makes Gaussian {exc.row} degenerate ({exc.reason}); "
                                  "use a milder transform", json_path=edit.json_path,
                                  path=source) from None
        disp = float(np.sqrt(((new.positions - scene.positions) ** 2).sum(1)).max())
        i_sup = basis.indices
        # distortion of the proxy discs carried by the Jacobians (the same figures
        # as for plain splats; the new proxy's axes may swap order, so not from it)
        jac = basis.jacobians(d_c)
        u, v = proxy.u[i_sup], proxy.v[i_sup]
        dist = distortion_from_axes(u, v, np.einsum("nij,nj->ni", jac, u), np.einsum("nij,nj->ni", jac, v))
        stats = basis.stats
        con = basis.constraints
        rep = EditReport(i, len(con.support_index), [len(h) for h in con.handle_index],
                         stats["n_constraints"], stats["n_centers"], stats["residual"], stats["method"],
                         stats["fit_seconds"], stats["basis_seconds"] + (time.perf_counter() - t0), disp,
                         [stats["message"]] if stats.get("message") else [],
                         [(c.n_controls, n) for c, n in zip(r.curves, stats.get("n_curve_samples", []))],
                         stats.get("closure_added", 0),
                         [f"edit {i}: {c.describe(con.spacing)}" for c in con.conflicts], dist)
        reports.append(rep)
        if on_edit is not None:
            on_edit(rep)
        scene = new
    return scene, reports

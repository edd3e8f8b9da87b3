"""Gaussian Splatting scenes as editor documents (issue 13).

The editor's session, tools, history and fits work on a
:class:`~splatedit.model.cloud.SplatCloud`.  A 3DGS/2DGS scene enters as its
splat proxy (:meth:`GaussianCloud.proxy_splats`: one disc per Gaussian, same
index, the proxy ``splatedit deform`` fits its edits on, so a saved edit
script replays to the same file) with the :class:`GaussianCloud` attached to
it.  Everything that keeps a cloud (undo snapshots, the viewport, saves)
therefore keeps the matching Gaussians; a cloud derived from the proxy
(``replace``, ``subset``, a deformed copy) has no Gaussians attached.

* the viewport draws :func:`gaussians_of` its cloud with the Gaussian renderer
  (live deformation on the GPU: centres, J Sigma J^T, SH frames);
* a commit deforms the Gaussians on the CPU (:func:`commit_cloud`: covariance
  re-decomposition and SH rotation, :mod:`splatedit.deform.gaussians`) and
  attaches them to their new proxy;
* a save writes the attached Gaussians as a 3DGS PLY (unknown properties kept).
"""

from __future__ import annotations

from splatedit.model.gaussians import GaussianCloud

_ATTR = "_splatedit_gaussians"

#: why a Gaussian document has no detail mode (as ``splatedit deform`` refuses it): the
#: Gaussians' transport needs the plain basis' displacements and Jacobians
DETAIL_UNAVAILABLE = "the detail mode is not available for Gaussian scenes (rotation and linear are)"


def gaussian_document(scene: GaussianCloud):
    """The proxy SplatCloud of ``scene`` with ``scene`` attached (n splats, same indices)."""
    proxy = scene.proxy_splats()
    object.__setattr__(proxy, _ATTR, scene)
    return proxy


def gaussians_of(cloud) -> GaussianCloud | None:
    """The Gaussian scene behind an editor document, or None for plain splats."""
    return getattr(cloud, _ATTR, None) if cloud is not None else None


def commit_cloud(basis, cloud, dc, progress=None, mode=None, matrices=(), outcome=None):
    """The editor's commit of one edit: ``basis.commit`` for plain splats
    (with ``mode`` given, the deformation mode's refinement of needles for
    the handles' ``matrices``, as ``splatedit deform`` does:
    :func:`~splatedit.deform.refine.refine_committed`; ``outcome``, a dict,
    gets ``"refined"``: its note or ""); for
    a Gaussian document the Gaussians deformed on the CPU by the basis and
    ``dc`` ((K, 3) or a RotationDisplacement) and re-wrapped as a new document.
    ``progress``: optional ``progress(stage, fraction)`` after each chunk
    (raising in it abandons the commit; ``cloud`` is never modified).

    Raises:
        InputError: a splat (or Gaussian) degenerates; nothing changes.
    """
    scene = gaussians_of(cloud)
    if scene is None:
        new = basis.commit(cloud, dc, progress=progress)
        if mode is not None:
            from splatedit.deform.refine import refine_committed
            new, _, note = refine_committed(basis, cloud, new, mode, matrices)
            if outcome is not None:
                outcome["refined"] = note
        return new
    if not (hasattr(basis, "displacements") and hasattr(basis, "jacobians")):     # a DetailBasis
        from splatedit.errors import SplatEditError
        raise SplatEditError(DETAIL_UNAVAILABLE)
    from splatedit.deform.gaussians import deform_with_evaluator
    return gaussian_document(deform_with_evaluator(scene, basis, dc, progress=progress))


def subset_document(cloud, kept):
    """The document with only the splats ``kept`` ((n,) bool) in order (a
    delete or crop): plain splats through ``SplatCloud.subset`` (faces
    dropped), a Gaussian document as the same subset of its Gaussians (what
    ``splatedit deform`` replaying the script's delete / crop gives)."""
    scene = gaussians_of(cloud)
    if scene is None:
        return cloud.subset(kept)
    return gaussian_document(scene.take(kept))


def document_bytes(cloud) -> int:
    """Bytes of the arrays a Gaussian document adds to its proxy (history budget)."""
    g = gaussians_of(cloud)
    if g is None:
        return 0
    return int(sum(a.nbytes for a in (g.positions, g.log_scales, g.rotations, g.opacity_logits, g.sh)))


def describe(scene: GaussianCloud) -> str:
    """One line for the status message: count, kind, SH degree."""
    return f"{len(scene):,} Gaussians ({scene.kind.value}, SH degree {scene.sh_degree})"


def model_summary(cloud) -> str:
    """What the document holds, for the panel and the load message:
    ``37,706 splats`` or ``5,000 Gaussians (3dgs, SH degree 3)``."""
    scene = gaussians_of(cloud)
    return f"{cloud.n:,} splats" if scene is None else describe(scene)

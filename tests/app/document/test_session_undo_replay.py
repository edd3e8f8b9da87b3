"""Issue 19 item 2: after undo / redo the next move starts from exactly the
restored document (basis, handle frame, pivot, pose), so every file the
session saves equals ``splatedit deform`` replaying the edit script saved
beside it.

Root cause of the bug: a committed cloud is a shallow copy of its base
(``copy.copy`` in ``DeformationBasis.apply``) and carried its revision
number along, so the fit key of the restored base equalled the deformed
cloud's and the basis fitted on the deformed cloud (controls moved by the
undone move) was kept for the next edit (see :mod:`splatedit.app.document.revision`).

The replay goes through the command line's own entry (``splatedit.cli.main
deform``), the saved file through the writer the editor's Ctrl+S uses.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from splatedit.app.document.session import GRAB, ROTATE, SCALE, Session
from splatedit.cli import main
from splatedit.io import read, write
from splatedit.select.selection import HANDLE, SUPPORT
from splatedit.model import SplatCloud
from tests.app.sessions import view

#: the saved file and the replay of its script agree within this fraction of
#: the model's diagonal (measured: 0 -- the same arrays, the same fit; the
#: bug this guards against was 0.14 / 1.6 = 0.09 of the diagonal)
REPLAY_TOL_OF_DIAGONAL = 1e-9


def save_and_replay(s: Session, src: Path, folder: Path, name: str) -> float:
    """Save ``s`` as the editor's Ctrl+S does (the cloud with ``io.write``,
    the script beside it) and replay the script on ``src`` with ``splatedit
    deform``; the largest position / axis difference over the diagonal."""
    out, spath, again = folder / f"{name}.ply", folder / f"{name}.edits.json", folder / f"{name}-replay.ply"
    write(str(out), s.cloud, overwrite=True)
    s.edit_script().save(spath)
    assert main(["-q", "deform", str(src), "--edit", str(spath), "-o", str(again), "-f"]) == 0
    a, b = read(str(out)), read(str(again))
    diff = max(float(np.abs(getattr(a, k) - getattr(b, k)).max()) for k in ("positions", "u", "v"))
    return diff / a.diagonal


def move(s: Session, mode: str, axis, text: str) -> str:
    """A typed G/R/S of the active handle (``G X 0.1 Enter``), after the fit
    ("" when there is nothing to move: undo went back before the handle)."""
    if not s.wait_fit():
        return ""
    assert s.begin(mode, view(), (100.0, 100.0))
    if axis is not None:
        s.manip.set_axis(axis)
    for ch in text:
        s.manip.type_char(ch)
    return s.finish()


def test_undo_then_rotate_on_the_bunny_saves_what_its_script_replays(tmp_path):
    """The issue's sequence: ear as support, its tip as handle, G X 0.1
    Enter, Ctrl+Z, R 90 Enter, save: the tip turns about its own centre (it
    does not jump by the undone 0.1) and the file is its script's replay."""
    from splatedit.data import default_model_path
    src = Path(default_model_path())
    s = Session(read(str(src)), fit_sync=True)
    try:
        p = s.cloud.positions
        ear, tip = p[:, 1] > np.percentile(p[:, 1], 92), p[:, 1] > np.percentile(p[:, 1], 99)
        s.brush_target = SUPPORT
        s.end_stroke(s.paint(np.flatnonzero(ear)))
        s.brush_target = HANDLE
        s.end_stroke(s.paint(np.flatnonzero(tip)))
        base = s.cloud
        assert move(s, GRAB, 0, "0.1") == "commit"
        assert s.undo() and s.cloud is base
        assert move(s, ROTATE, None, "90") == "commit"
        centre_before, centre_after = base.positions[tip].mean(0), s.cloud.positions[tip].mean(0)
        assert np.linalg.norm(centre_after - centre_before) < 1e-9 * base.diagonal   # turned in place
        assert save_and_replay(s, src, tmp_path, "bunny-edited") <= REPLAY_TOL_OF_DIAGONAL
    finally:
        s.close()


def bumpy_cloud(k: int = 14) -> SplatCloud:
    """k x k splats on a gently curved square (not flat: rotations about any axis change it)."""
    xs, ys = np.meshgrid(np.linspace(-1, 1, k), np.linspace(-1, 1, k))
    z = 0.15 * np.sin(2.0 * xs) * np.cos(1.5 * ys)
    p = np.c_[xs.ravel(), ys.ravel(), z.ravel()]
    r = 2.0 / (k - 1)
    n = len(p)
    return SplatCloud(p, np.tile([r, 0, 0], (n, 1)), np.tile([0, r, 0], (n, 1)), name="bumpy")


MOVES = st.one_of(
    st.tuples(st.just(GRAB), st.sampled_from([0, 1, 2]), st.sampled_from(["0.1", "-0.05", "0.2"])),
    st.tuples(st.just(ROTATE), st.sampled_from([None, 0, 1]), st.sampled_from(["90", "30", "-45"])),
    st.tuples(st.just(SCALE), st.sampled_from([None, 2]), st.sampled_from(["1.3", "0.8"])))
STEPS = st.lists(st.one_of(MOVES, st.sampled_from(["undo", "redo", "save"])), min_size=2, max_size=7)


@settings(max_examples=12, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(steps=STEPS)
def test_every_save_after_random_edits_undo_redo_equals_the_replay_of_its_script(steps):
    """Random sequences of typed translate / rotate / scale moves of the
    handle, undo, redo and save: every save (and one at the end) equals the
    replay of its own saved script within REPLAY_TOL_OF_DIAGONAL."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        src = folder / "bumpy.ply"
        cloud = bumpy_cloud()
        write(str(src), cloud)
        s = Session(read(str(src)), fit_sync=True)
        try:
            r = np.linalg.norm(s.cloud.positions[:, :2] - [0.3, 0.0], axis=1)
            s.brush_target = SUPPORT
            s.end_stroke(s.paint(np.flatnonzero(r < 0.75)))
            s.brush_target = HANDLE
            s.end_stroke(s.paint(np.flatnonzero(r < 0.2)))
            for i, step in enumerate(steps + ["save"]):
                if step == "undo":
                    s.undo()
                elif step == "redo":
                    s.redo()
                elif step == "save":
                    if s.edits:
                        assert save_and_replay(s, src, folder, f"save{i}") <= REPLAY_TOL_OF_DIAGONAL, steps
                else:
                    move(s, *step)
        finally:
            s.close()


def test_undo_of_a_curve_edit_draws_its_pending_bend_at_once_dots_on_the_surface():
    """Issue 19 item 8: after undoing a committed curve edit its (pending)
    dots floated over the undeformed surface until the basis was refitted.
    The basis of the restored document is taken back at once (no fit job):
    the splat under each moved dot is drawn at the dot."""
    from tests.app.sessions import plane_cloud
    s = Session(plane_cloud(), fit_sync=True)
    try:
        p = s.cloud.positions
        s.brush_target = SUPPORT
        s.end_stroke(s.paint(np.flatnonzero(np.linalg.norm(p[:, :2], axis=1) < 0.8)))
        picked = [int(np.argmin(np.linalg.norm(p - [x, 0.0, 0.0], axis=1))) for x in (-0.4, 0.0, 0.4)]
        for i in picked:
            assert s.add_curve_point(p[i])
        assert s.wait_fit() and s.begin_curve_point(2, view(), (100.0, 100.0))
        s.manip.set_axis(2)
        for ch in "0.2":
            s.manip.type_char(ch)
        assert s.finish() == "pose" and s.commit() and not s.curve_points
        assert s.undo() and len(s.curve_points) == 3
        assert s.fit_job is None and s.basis is not None           # taken back, not refitted
        dots = s.curve_point_positions()
        drawn = s.basis.apply(s.cloud, s.current_dc()).positions[picked]
        # on the surface within 1 % of the move (the curve is met through its samples; a
        # floating dot is off by the whole move, 0.2)
        assert np.abs(drawn - dots).max() < 0.01 * 0.2 and abs(dots[2, 2] - 0.2) < 1e-12
        assert s.redo() and not s.curve_points and len(s.edits) == 1      # nothing left to fit
    finally:
        s.close()

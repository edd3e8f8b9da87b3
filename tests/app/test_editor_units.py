"""Editor helpers that need no window: save paths, options, controls text."""

import argparse
from pathlib import Path

from splatedit.app.editor import CONTROLS, _default_save_path, add_arguments, options_from_args, script_path_for


def test_default_save_path_next_to_input_never_the_input(tmp_path, monkeypatch):
    src = tmp_path / "scan.ply"
    src.write_bytes(b"x")
    p = _default_save_path(src, "scan.ply", bundled=False)
    assert p == tmp_path / "scan-edited.ply" and p != src
    p.write_bytes(b"old")                       # an existing result is not clobbered
    assert _default_save_path(src, "scan.ply", bundled=False) == tmp_path / "scan-edited-2.ply"


def test_bundled_model_saves_to_current_dir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    pkg = Path("/nonexistent/site-packages/splatedit/data/bunny.ply")
    assert _default_save_path(pkg, "bunny.ply", bundled=True) == tmp_path / "bunny-edited.ply"


def test_script_path_and_options():
    assert script_path_for(Path("/a/b/x-edited.ply")) == Path("/a/b/x-edited.edits.json")
    p = argparse.ArgumentParser()
    add_arguments(p)
    o = options_from_args(p.parse_args(["m.ply", "--size", "800x600", "--save-as", "o.ply", "--no-vsync"]))
    assert o["size"] == (800, 600) and o["save_as"] == "o.ply" and o["vsync"] is False


def test_controls_document_every_required_binding():
    for needle in ("Middle drag", "Shift + middle", "Wheel", "Home", "numpad .", "Alt + left",
                   "G / R / S", "X / Y / Z", "Ctrl+Z", "Ctrl+Shift+Z", "Ctrl+S", "Ctrl+Shift+S",
                   "F1", "[ / ]", "Esc"):
        assert needle in CONTROLS, needle


def test_default_save_path_keeps_scanner_formats(tmp_path):
    """A LAS / LAZ / E57 scan is saved in its own format (its intensity,
    classification and georeference survive, as CloudCompare users expect);
    text formats go to the lossless splat PLY."""
    for name, expected in (("scan.las", "scan-edited.las"), ("scan.LAZ", "scan-edited.laz"),
                           ("site.e57", "site-edited.e57"), ("pts.xyz", "pts-edited.ply"),
                           ("scan.pcd", "scan-edited.ply")):
        src = tmp_path / name
        src.write_bytes(b"")
        assert _default_save_path(src, name, bundled=False) == tmp_path / expected


def test_a_model_opened_by_a_path_inside_the_package_is_saved_in_the_users_folder(tmp_path, monkeypatch):
    """``splatedit edit .../splatedit/data/bunny.ply`` (a path, so not "the
    bundled model"): the proposed save is in the current directory, never
    beside the shipped file; from a current directory inside the package it
    is the home folder; an explicit save into the package is refused."""
    from splatedit.app.document.files import inside_package, package_folder, save_refusal
    from splatedit.data import default_model_path
    src = default_model_path()
    assert inside_package(src) and not inside_package(tmp_path)
    monkeypatch.chdir(tmp_path)
    assert _default_save_path(src, src.name, bundled=False) == tmp_path / "bunny-edited.ply"
    monkeypatch.chdir(package_folder() / "data")
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    assert _default_save_path(src, src.name, bundled=False) == home / "bunny-edited.ply"
    into = package_folder() / "data" / "bunny-edited.ply"
    assert "inside the installed splatedit package" in save_refusal(into, src)
    assert save_refusal(tmp_path / "bunny-edited.ply", src) is None

"""Recent files: most recent first, at most RECENT_MAX, missing files dropped,
kept in $XDG_CONFIG_HOME/splatedit/recent.json and written atomically."""

from __future__ import annotations

import json

from splatedit.app.ui.recent import RECENT_MAX, RecentFiles, recent_path


def _models(tmp_path, n):
    out = []
    for i in range(n):
        p = tmp_path / f"m{i}.ply"
        p.write_text("x")
        out.append(p)
    return out


def test_list_lives_in_the_xdg_config_folder(private_config, tmp_path):
    assert recent_path() == private_config / "splatedit" / "recent.json"
    (m,) = _models(tmp_path, 1)
    RecentFiles().add(m)
    data = json.loads(recent_path().read_text())
    assert data["files"] == [str(m)]
    # atomic write: nothing but the list is left in the folder
    assert [p.name for p in recent_path().parent.iterdir()] == ["recent.json"]


def test_most_recent_first_without_duplicates_and_capped(tmp_path):
    models = _models(tmp_path, RECENT_MAX + 3)
    r = RecentFiles(tmp_path / "cfg" / "recent.json")
    for m in models:
        r.add(m)
    r.add(models[5])                       # opened again: moves to the top, once
    got = r.files()
    assert len(got) == RECENT_MAX
    assert got[0] == models[5]
    assert got[1:] == [m for m in reversed(models) if m != models[5]][:RECENT_MAX - 1]


def test_missing_files_are_dropped_and_relative_paths_made_absolute(tmp_path, monkeypatch):
    a, b = _models(tmp_path, 2)
    monkeypatch.chdir(tmp_path)
    r = RecentFiles(tmp_path / "recent.json")
    r.add(a.name)
    r.add(b)
    assert r.files() == [b, a]
    b.unlink()
    assert r.files() == [a]


def test_malformed_or_unreadable_list_is_empty(tmp_path):
    path = tmp_path / "recent.json"
    r = RecentFiles(path)
    for text in ("not json", "[1, 2]", '{"files": "a"}', '{"files": [3, null, ""]}'):
        path.write_text(text)
        assert r.files() == []
    (m,) = _models(tmp_path, 1)
    r.add(m)                               # a bad list is replaced by a good one
    assert r.files() == [m]

"""The cache folder (issue 15 item 5, issue 16 item 4): entries keyed on the code that made
them, a damaged entry rebuilt, entries older code left behind deleted, never the user's files."""
from __future__ import annotations

import os
import time

import numpy as np

from app.files.cache import clear, entries, prune, total_bytes


def _fill(root):
    """A cache as several code versions leave it, plus a file of the user's."""
    (root / "manifolds").mkdir(parents=True)
    made = {}
    for k, (name, size) in enumerate([
        ("synthetic-default-old1.npz", 300), ("synthetic-default-old1-audio/a.wav", 20),
        ("synthetic-default-cur.npz", 400), ("synthetic-default-cur-audio/a.wav", 30),
        ("synthetic-small-other.npz", 100), ("manifolds/synthetic-default-g3-aaa-m1-old-0.1.0.npz", 500),
        ("manifolds/synthetic-default-g3-bbb-m1-cur-0.1.0.npz", 600),
        ("manifolds/synthetic-small-g3-ccc-m1-x-0.1.0.npz", 50), (".synthetic-default-cur.x1.part.npz", 7),
        ("notes.txt", 5), ("synthetic-default-notes.txt", 5),
    ]):
        p = root / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(bytes(size))
        os.utime(p, (time.time() - 100 + k, time.time() - 100 + k))
        made[name] = p
    return made


def test_entries_and_sizes_count_only_lipspace_files(tmp_path):
    _fill(tmp_path)
    kinds = sorted((e.path.relative_to(tmp_path).as_posix(), e.kind, e.preset, e.size) for e in entries(tmp_path))
    assert kinds == [
        (".synthetic-default-cur.x1.part.npz", "partial", "", 7),
        ("manifolds/synthetic-default-g3-aaa-m1-old-0.1.0.npz", "manifold", "default", 500),
        ("manifolds/synthetic-default-g3-bbb-m1-cur-0.1.0.npz", "manifold", "default", 600),
        ("manifolds/synthetic-small-g3-ccc-m1-x-0.1.0.npz", "manifold", "small", 50),
        ("synthetic-default-cur-audio", "audio", "default", 30),
        ("synthetic-default-cur.npz", "corpus", "default", 400),
        ("synthetic-default-old1-audio", "audio", "default", 20),
        ("synthetic-default-old1.npz", "corpus", "default", 300),
        ("synthetic-small-other.npz", "corpus", "small", 100),
    ]
    assert total_bytes(tmp_path) == 2007


def test_prune_deletes_what_older_code_left_for_the_same_preset_only(tmp_path):
    made = _fill(tmp_path)
    gone = prune([made["manifolds/synthetic-default-g3-bbb-m1-cur-0.1.0.npz"], made["synthetic-default-cur.npz"]],
                 tmp_path)
    assert sorted(e.path.name for e in gone) == ["synthetic-default-g3-aaa-m1-old-0.1.0.npz",
                                                 "synthetic-default-old1-audio", "synthetic-default-old1.npz"]
    left = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*") if p.is_file())
    assert left == [".synthetic-default-cur.x1.part.npz", "manifolds/synthetic-default-g3-bbb-m1-cur-0.1.0.npz",
                    "manifolds/synthetic-small-g3-ccc-m1-x-0.1.0.npz", "notes.txt", "synthetic-default-cur-audio/a.wav",
                    "synthetic-default-cur.npz", "synthetic-default-notes.txt", "synthetic-small-other.npz"]


def test_clear_and_the_cache_command(tmp_path, monkeypatch, capsys):
    from app.cli import main

    _fill(tmp_path)
    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path))
    assert main(["cache"]) == 0
    out = capsys.readouterr().out
    assert f"cache folder {tmp_path}" in out and "LIPSPACE_CACHE_DIR" in out and "total 0.0 MB" in out
    assert "synthetic talker corpora     3" in out and "manifolds fitted to them     3" in out, out
    assert main(["cache", "--clear"]) == 0
    assert "removed 9 entries" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt", "synthetic-default-notes.txt"]
    assert main(["cache", "--clear"]) == 0 and "removed 0 entries" in capsys.readouterr().out


def test_window_cache_uses_the_current_entry_rebuilds_a_damaged_one_and_prunes(small_manifold, small_corpus,
                                                                             monkeypatch, tmp_path):
    import engine.talker.synthetic
    from app.files.source_loading import cached_manifold_path, load_source

    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path))
    old = tmp_path / "manifolds" / "synthetic-small-g1-0000-m1-0000-0.0.1.npz"  # made by older code
    old.parent.mkdir(parents=True)
    old.write_bytes(b"PK\x03\x04 an old manifold")
    cur = small_manifold.save(cached_manifold_path("small"))
    stages = []
    m, _ = load_source(None, "small", lambda st, d, t: stages.append(st), prepare_views=False)
    assert set(stages) == {"loading cached manifold"} and not old.exists()  # used, and the old entry deleted
    np.testing.assert_array_equal(m.Fy_, small_manifold.Fy_)
    cur.write_bytes(cur.read_bytes()[:1000])  # damaged (cut short): rebuilt, never used
    tiny = small_corpus.subset([u.id for u in small_corpus.utterances[:4]])
    monkeypatch.setattr(engine.talker.synthetic, "load_synthetic", lambda **kw: tiny)
    stages.clear()
    m2, _ = load_source(None, "small", lambda st, d, t: stages.append(st), prepare_views=False)
    assert "loading cached manifold" in stages and len(set(stages)) > 1  # tried, then fitted anew
    assert m2.Fy_.shape[0] == tiny.n_frames != small_manifold.Fy_.shape[0]
    from engine.manifold.model import Manifold

    assert Manifold.load(cur).Fy_.shape[0] == tiny.n_frames  # the damaged entry was replaced


def test_cache_and_state_folders_follow_one_rule(monkeypatch, tmp_path):
    from app.files.autosave import state_dir
    from app.files.cache import cache_dir
    from engine.talker.synthetic import cache_folder

    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path / "c"))
    monkeypatch.setenv("LIPSPACE_STATE_DIR", str(tmp_path / "s"))
    assert cache_dir() == cache_folder() == tmp_path / "c" and state_dir() == tmp_path / "s"
    assert cache_folder(tmp_path / "o") == tmp_path / "o"


def test_method_choices_are_entries_and_cleared(tmp_path, small_manifold):
    """The measured choice of synthesis method per corpus (engine.synthesis.method_choice) is Lipspace's to list and clear."""
    from engine.synthesis.method_choice import choice_path

    mine = choice_path(small_manifold, tmp_path)
    mine.parent.mkdir(parents=True)
    mine.write_text("{}")
    other = mine.parent / "notes.json"
    other.write_text("{}")
    found = [(e.path, e.kind) for e in entries(tmp_path)]
    assert found == [(mine, "method choice")]
    assert [e.path for e in clear(tmp_path)] == [mine]
    assert other.exists() and not mine.exists()

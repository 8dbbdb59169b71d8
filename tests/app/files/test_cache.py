"""The cache folder (issue 15 item 5, issue 16 item 4): entries keyed on the code that made
them, a damaged entry rebuilt, entries older code left behind deleted, never the user's files."""
from __future__ import annotations

import os
import time

import numpy as np

from app.files.cache import clear, entries, prune, total_bytes


#: a process id that no longer runs (temporary files named after it were left by a killed run)
def _dead_pid():
    import subprocess
    import sys

    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


#: the user's files named like cache entries (never marked, never deleted)
USERS = ("synthetic-default-mine.npz", "manifolds/synthetic-default-kept-by-me.npz")


def _fill(root):
    """A cache as several code versions leave it (each entry marked as Lipspace's when written), plus the
    user's own files, two of them named like entries."""
    from engine.files.ownership import mark

    (root / "manifolds").mkdir(parents=True)
    made = {}
    dead = _dead_pid()
    for k, (name, size) in enumerate([
        ("synthetic-default-old1.npz", 300), ("synthetic-default-old1-audio/a.wav", 20),
        ("synthetic-default-cur.npz", 400), ("synthetic-default-cur-audio/a.wav", 30),
        ("synthetic-small-other.npz", 100), ("manifolds/synthetic-default-g3-aaa-m1-old-0.1.0.npz", 500),
        ("manifolds/synthetic-default-g3-bbb-m1-cur-0.1.0.npz", 600),
        ("manifolds/synthetic-small-g3-ccc-m1-x-0.1.0.npz", 50),
        (f".synthetic-default-cur.p{dead}-x1y2z3w4.part.npz", 7),
        ("notes.txt", 5), ("synthetic-default-notes.txt", 5),
        ("synthetic-default-mine.npz", 9), ("manifolds/synthetic-default-kept-by-me.npz", 11),
    ]):
        p = root / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(bytes(size))
        os.utime(p, (time.time() - 100 + k, time.time() - 100 + k))
        made[name] = p
        if name not in USERS and not name.endswith((".txt", ".part.npz")):
            mark(p.parent if name.endswith(".wav") else p, root)
    return made


def _owned(root):
    return sorted(e.path.relative_to(root).as_posix() for e in entries(root) if e.owned)


def test_entries_and_sizes_count_only_lipspace_files(tmp_path):
    made = _fill(tmp_path)
    part = next(n for n in made if n.endswith(".part.npz"))
    kinds = sorted((e.path.relative_to(tmp_path).as_posix(), e.kind, e.preset, e.size) for e in entries(tmp_path)
                   if e.owned)
    assert kinds == [
        (part, "partial", "", 7),
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
    # named like entries, but never written by the cache: listed as not Lipspace's
    assert sorted(e.path.name for e in entries(tmp_path) if not e.owned) == ["synthetic-default-kept-by-me.npz",
                                                                               "synthetic-default-mine.npz"]


def test_a_users_file_at_an_entrys_name_is_not_the_caches(tmp_path):
    """Copied over a marked entry (its size or time changes), or put at the name of a deleted one: the user's."""
    made = _fill(tmp_path)
    cur = made["synthetic-default-cur.npz"]
    cur.write_bytes(b"the user's own data")
    old = made["synthetic-default-old1.npz"]
    old.unlink()
    old.write_bytes(bytes(300))
    assert not {cur.name, old.name} & {p.rsplit("/", 1)[-1] for p in _owned(tmp_path)}
    clear(tmp_path)
    assert cur.read_bytes() == b"the user's own data" and old.exists()
    assert made["synthetic-default-mine.npz"].exists() and made["manifolds/synthetic-default-kept-by-me.npz"].exists()


def test_prune_deletes_what_older_code_left_for_the_same_preset_only(tmp_path):
    made = _fill(tmp_path)
    gone = prune([made["manifolds/synthetic-default-g3-bbb-m1-cur-0.1.0.npz"], made["synthetic-default-cur.npz"]],
                 tmp_path)
    assert sorted(e.path.name for e in gone) == ["synthetic-default-g3-aaa-m1-old-0.1.0.npz",
                                                 "synthetic-default-old1-audio", "synthetic-default-old1.npz"]
    part = next(n for n in made if n.endswith(".part.npz"))
    left = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*") if p.is_file()
                  and ".lipspace-entries" not in p.parts)
    assert left == sorted([part, "manifolds/synthetic-default-g3-bbb-m1-cur-0.1.0.npz",
                           "manifolds/synthetic-small-g3-ccc-m1-x-0.1.0.npz", "notes.txt",
                           "synthetic-default-cur-audio/a.wav", "synthetic-default-cur.npz",
                           "synthetic-default-notes.txt", "synthetic-small-other.npz", "synthetic-default-mine.npz",
                           "manifolds/synthetic-default-kept-by-me.npz"])


def test_clear_and_the_cache_command(tmp_path, monkeypatch, capsys):
    from app.cli import main

    _fill(tmp_path)
    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path))
    assert main(["cache"]) == 0
    out = capsys.readouterr().out
    assert f"cache folder {tmp_path}" in out and "LIPSPACE_CACHE_DIR" in out and "total 0.0 MB" in out
    assert "synthetic talker corpora     3" in out and "manifolds fitted to them     3" in out, out
    assert main(["cache", "--clear"]) == 0
    out, err = capsys.readouterr()
    assert "removed 9 entries" in out and "2 files named like cache entries" in err, (out, err)
    assert sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*")) == [
        "manifolds", "manifolds/synthetic-default-kept-by-me.npz", "notes.txt", "synthetic-default-mine.npz",
        "synthetic-default-notes.txt"]
    assert main(["cache", "--clear"]) == 0 and "removed 0 entries" in capsys.readouterr().out


def test_window_cache_uses_the_current_entry_rebuilds_a_damaged_one_and_prunes(small_manifold, small_corpus,
                                                                             monkeypatch, tmp_path):
    import engine.talker.talker_cache
    from app.files.source_loading import cached_manifold_path, load_source

    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path))
    old = tmp_path / "manifolds" / "synthetic-small-g1-0000-m1-0000-0.0.1.npz"  # made by older code
    old.parent.mkdir(parents=True)
    old.write_bytes(b"PK\x03\x04 an old manifold")
    from engine.files.ownership import mark

    mark(old, tmp_path)  # written (and marked) by the cache of older code
    cur = small_manifold.save(cached_manifold_path("small"))
    stages = []
    m, _ = load_source(None, "small", lambda st, d, t: stages.append(st), prepare_views=False)
    assert set(stages) == {"loading cached manifold"} and not old.exists()  # used, and the old entry deleted
    np.testing.assert_array_equal(m.Fy_, small_manifold.Fy_)
    cur.write_bytes(cur.read_bytes()[:1000])  # damaged (cut short): rebuilt, never used
    tiny = small_corpus.subset([u.id for u in small_corpus.utterances[:4]])
    monkeypatch.setattr(engine.talker.talker_cache, "load_synthetic", lambda **kw: tiny)
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
    """The measured choice of synthesis method per corpus (engine.synthesis.method_choice) is Lipspace's to list and
    clear."""
    from engine.synthesis.method_choice import choice_path

    mine = choice_path(small_manifold, tmp_path)
    mine.parent.mkdir(parents=True)
    mine.write_text("{}")
    other = mine.parent / "notes.json"
    other.write_text("{}")
    found = [(e.path, e.kind, e.owned) for e in entries(tmp_path)]
    assert found == [(mine, "method choice", False)]  # not written by the cache: never deleted
    assert clear(tmp_path) == [] and mine.exists()
    from engine.files.ownership import mark

    mark(mine, tmp_path)
    assert [e.path for e in clear(tmp_path)] == [mine]
    assert other.exists() and not mine.exists()

"""The synthetic talker's two kinematics in the explorer's loading (Qt-free): the cache keeps
the classic and the calibrated talker apart, a wrong kinematics is refused with the choices,
and a session keeps the talker it was saved with."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

from app.files.cache import entries
from app.files.session import SessionError, load_session, save_session, source_kinematics
from app.files.source_loading import (
    KINEMATICS_CHOICES,
    cached_manifold_path,
    check_kinematics,
    load_source,
    talker_name,
)
from app.models.state import AppState


def test_cache_names_keep_the_talkers_apart_and_the_classic_name_unchanged(monkeypatch, tmp_path):
    from engine import __version__
    from engine.manifold.model import FILE_VERSION, algorithm_fingerprint
    from engine.talker.synthetic import GENERATOR_VERSION, generator_fingerprint

    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path))
    classic = cached_manifold_path("default")
    # the name the classic talker's manifold had before the talker had a choice of kinematics
    assert classic == tmp_path / "manifolds" / (f"synthetic-default-g{GENERATOR_VERSION}-{generator_fingerprint()}-"
                                                f"m{FILE_VERSION}-{algorithm_fingerprint()}-{__version__}.npz")
    assert cached_manifold_path("default", "classic") == classic
    calibrated = cached_manifold_path("default", "calibrated")
    assert calibrated != classic and calibrated.parent == classic.parent
    assert calibrated.name.startswith("synthetic-default_calibrated-g")
    assert calibrated.name.split("-", 2)[2] == classic.name.split("-", 2)[2]  # the same key after the talker
    for p in (classic, calibrated):
        p.parent.mkdir(exist_ok=True)
        p.write_bytes(b"x")
    # the cache reads each name's talker apart, which is what pruning goes by
    assert sorted(e.preset for e in entries(tmp_path)) == ["default", "default_calibrated"]


def test_a_wrong_kinematics_is_refused_naming_it_and_the_choices(small_manifold, tmp_path):
    from engine.talker.lipmodel import KINEMATICS

    assert KINEMATICS_CHOICES == tuple(KINEMATICS)  # the command line's choices are the engine's
    for call in (lambda: check_kinematics("calibrate"), lambda: cached_manifold_path("small", "calibrate"),
                 lambda: load_source(None, "small", kinematics="calibrate", use_cache=False)):
        with pytest.raises(ValueError) as exc:
            call()
        msg = str(exc.value)
        assert "'calibrate'" in msg and "'classic'" in msg and "'calibrated'" in msg, msg
    assert check_kinematics("calibrated") == "calibrated"
    # a file holds its own frames: the talker's kinematics with a file is refused, the file not read
    mfile = small_manifold.save(tmp_path / "m.npz")
    with pytest.raises(ValueError, match="does nothing with a file .*m.npz"):
        load_source(mfile, kinematics="calibrated")
    m, src = load_source(mfile, prepare_views=False)
    assert "kinematics" not in src and src["kind"] == "manifold"  # only the synthetic talker's source has it


def test_talker_names():
    assert talker_name("small") == "synthetic talker (small)"  # as the window always named it
    assert talker_name("default", "calibrated") == "synthetic talker (default, calibrated on articulograph lips)"


def _touch(path, data=b"x", age_s=0.0):
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".npz":
        path.write_bytes(data)
    else:
        path.mkdir(exist_ok=True)
    if age_s:
        t = path.stat().st_mtime - age_s
        os.utime(path, (t, t))
    return path


def test_opening_one_talker_prunes_only_its_own_old_entries(small_manifold, monkeypatch, tmp_path):
    """Each talker's current manifold and corpus survive the other's opening; older code's
    entries of the talker just opened are deleted."""
    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path))
    classic_manifold = small_manifold.save(cached_manifold_path("small"))
    classic_corpus = _touch(tmp_path / "synthetic-small-cur.npz")
    classic_audio = _touch(tmp_path / "synthetic-small-cur-audio")
    stale_cal_manifold = _touch(tmp_path / "manifolds" / "synthetic-small_calibrated-g1-0000-m1-0000-0.0.1.npz",
                                age_s=3600)
    stale_cal_corpus = _touch(tmp_path / "synthetic-small_calibrated-old.npz", age_s=3600)
    from engine.files.ownership import mark

    for p in (classic_manifold, classic_corpus, classic_audio, stale_cal_manifold, stale_cal_corpus):
        mark(p, tmp_path)  # each written by the cache (of this or older code)

    stages = []
    m, src = load_source(None, "small", lambda st, d, t: stages.append(st), kinematics="calibrated",
                         prepare_views=False)
    assert src == {"path": None, "preset": "small", "kind": "synthetic", "kinematics": "calibrated"}
    assert "loading cached manifold" not in stages  # the classic talker's cached manifold is not taken for it
    assert np.ptp(m.corpus_.latent["jaw_forward"]) > 0.5  # the calibrated talker (the classic's stays 0)
    cal_manifold = cached_manifold_path("small", "calibrated")
    cal_corpora = [e.path for e in entries(tmp_path) if e.kind == "corpus" and e.preset == "small_calibrated"]
    assert cal_manifold.is_file() and len(cal_corpora) == 1 and cal_corpora[0] != stale_cal_corpus
    assert not stale_cal_manifold.exists() and not stale_cal_corpus.exists()  # its own old entries: pruned
    assert classic_manifold.is_file() and classic_corpus.is_file() and classic_audio.is_dir()  # the other's: kept

    stages.clear()
    m2, src2 = load_source(None, "small", lambda st, d, t: stages.append(st), prepare_views=False)
    assert src2["kinematics"] == "classic" and set(stages) == {"loading cached manifold"}
    np.testing.assert_array_equal(m2.Fy_, small_manifold.Fy_)
    assert cal_manifold.is_file() and cal_corpora[0].is_file()  # the classic's pruning keeps the calibrated's
    assert classic_corpus.is_file()  # the newest classic corpus is kept beside its manifold


def _state(manifold, source):
    s = AppState(manifold)
    s.source = source
    s.select_frame(12)
    return s


def test_a_session_keeps_the_talkers_kinematics(small_manifold, tmp_path):
    src = {"path": None, "preset": "small", "kind": "synthetic", "kinematics": "calibrated"}
    path = save_session(_state(small_manifold, src), tmp_path / "cal.lipspace.json")
    d = load_session(path)
    assert d["source"]["kinematics"] == "calibrated" and source_kinematics(d) == "calibrated"
    # a session written before the talker had kinematics opens the classic talker
    old = tmp_path / "old.lipspace.json"
    old.write_text(json.dumps({"lipspace_session": 2, "source": {"path": None, "preset": "small"}}))
    assert source_kinematics(load_session(old)) == "classic"
    # a file's session never asks for a talker's kinematics
    assert source_kinematics({"source": {"path": "/data/m.npz", "kinematics": "calibrated"}}) == "classic"
    bad = tmp_path / "bad.lipspace.json"
    bad.write_text(json.dumps({"lipspace_session": 2, "source": {"path": None, "preset": "small",
                                                                 "kinematics": "realistic"}}))
    with pytest.raises(SessionError) as exc:
        load_session(bad)
    assert "bad.lipspace.json" in str(exc.value) and "'realistic'" in str(exc.value)
    assert "'calibrated'" in str(exc.value)


def test_the_autosave_notices_another_talker(small_manifold):
    from app.files.autosave import session_fingerprint

    s = _state(small_manifold, {"path": None, "preset": "small", "kind": "synthetic", "kinematics": "classic"})
    before = session_fingerprint(s)
    s.source = dict(s.source, kinematics="calibrated")
    assert session_fingerprint(s)[0] != before[0] and '"kinematics": "calibrated"' in session_fingerprint(s)[0]

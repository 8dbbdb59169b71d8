"""``lipspace explore`` without opening a window: display check, inputs, loading and the cache."""
from __future__ import annotations

import argparse

import numpy as np
import pytest

from app.cli import CliError, explore
from app.cli.explore import EXIT_NO_DISPLAY, has_display
from app.files.source_loading import cached_manifold_path, load_source, source_kind
from engine.progress import Cancelled


def run_explore(argv):
    p = argparse.ArgumentParser(prog="lipspace explore")
    explore.add_arguments(p)
    return explore.run(p.parse_args(argv))


@pytest.fixture
def no_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")


@pytest.fixture
def fake_display(monkeypatch):
    """A DISPLAY whose server the display check takes as answering (the window itself is never opened)."""
    monkeypatch.setenv("DISPLAY", ":0")
    monkeypatch.setattr("app.display_check.display_problem", lambda *a, **k: None)


@pytest.mark.parametrize("argv", [[], ["--preset", "small"], ["--session", "s.json"]])
def test_no_display_explains_and_exits_3(no_display, capsys, argv):
    assert run_explore(argv) == EXIT_NO_DISPLAY
    err = capsys.readouterr().err
    assert "needs a display" in err and "xvfb-run -a lipspace explore" in err
    for cmd in ("lipspace build -o m.npz", "lipspace info m.npz", "lipspace figures m.npz -o figs/",
                "lipspace clusters", "lipspace synthesize", "lipspace evaluate"):
        assert cmd in err


def test_has_display():
    assert has_display({"DISPLAY": ":1"}, "linux")
    assert has_display({"WAYLAND_DISPLAY": "wayland-0"}, "linux")
    assert not has_display({}, "linux")
    assert has_display({}, "win32") and has_display({}, "darwin")


def test_bad_file_is_a_user_error(monkeypatch, tmp_path, fake_display):
    with pytest.raises(CliError, match="no such file"):
        run_explore([str(tmp_path / "missing.npz")])
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    with pytest.raises(CliError, match="not a Lipspace"):
        run_explore([str(junk)])
    bad_session = tmp_path / "s.json"
    bad_session.write_text("{}")
    import app.launching

    opened = []  # a session that cannot be opened is said, and the window opens without it
    monkeypatch.setattr(app.launching, "launch", lambda *a, **k: opened.append((a, k)) or 0)
    assert run_explore(["--session", str(bad_session)]) == 0
    (args, kw), = opened
    assert kw["session"] is None and len(kw["notes"]) == 1
    assert kw["notes"][0].startswith(f"--session {bad_session} was not opened: ") and \
        "not a Lipspace session" in kw["notes"][0]


def test_cache_path_follows_env(monkeypatch, tmp_path):
    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path))
    p = cached_manifold_path("small")
    assert p.parent.parent == tmp_path and "small" in p.name and p.suffix == ".npz"
    assert cached_manifold_path("paper") != p
    with pytest.raises(ValueError, match="preset"):
        cached_manifold_path("huge")


def test_load_source_manifold_corpus_and_cache(small_manifold, small_corpus, monkeypatch, tmp_path):
    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path / "cache"))
    mpath = small_manifold.save(tmp_path / "m.npz")
    assert source_kind(mpath) == "manifold"
    m, src = load_source(mpath)
    assert src["kind"] == "manifold" and src["path"] == str(mpath.resolve())
    np.testing.assert_array_equal(m.Fy_, small_manifold.Fy_)
    # the synthetic talker comes from the cache when the cache holds it
    small_manifold.save(cached_manifold_path("small"))
    stages = []
    m2, src2 = load_source(None, "small", lambda st, d, t: stages.append(st))
    assert src2 == {"path": None, "preset": "small", "kind": "synthetic", "kinematics": "classic"}
    assert stages and set(stages) == {"loading cached manifold", "preparing the views"}
    np.testing.assert_array_equal(m2.Fy_, small_manifold.Fy_)
    # a corpus file is fitted (a few utterances keep it quick); cancelling stops the fit
    cpath = small_corpus.subset([u.id for u in small_corpus.utterances[:5]]).save(tmp_path / "c.npz")
    assert source_kind(cpath) == "corpus"
    m3, src3 = load_source(cpath)
    assert src3["kind"] == "corpus" and m3.Fy_.shape[0] == sum(u.n_frames for u in small_corpus.utterances[:5])

    def cancel(*_a):
        raise Cancelled("stop")

    with pytest.raises(Cancelled):
        load_source(cpath, progress=cancel)
    with pytest.raises(ValueError, match="no such file"):
        source_kind(tmp_path / "nope.npz")


def test_lipspace_alone_is_explore(no_display, capsys):
    from app.cli import main

    assert main([]) == EXIT_NO_DISPLAY
    assert "xvfb-run -a lipspace explore" in capsys.readouterr().err


def test_kinematics_argument_reaches_the_window_and_is_refused_with_a_file(monkeypatch, tmp_path, small_manifold):
    """``lipspace explore --kinematics calibrated`` opens the calibrated synthetic talker; with a
    file it is refused with the reason before anything is opened."""
    import app.launching

    p = argparse.ArgumentParser(prog="lipspace explore")
    explore.add_arguments(p)
    assert p.parse_args([]).kinematics == "classic"
    assert p.parse_args(["--preset", "small", "--kinematics", "calibrated"]).kinematics == "calibrated"
    with pytest.raises(SystemExit) as exc:
        p.parse_args(["--kinematics", "realistic"])
    assert exc.value.code == 2
    monkeypatch.setenv("DISPLAY", ":0")  # inputs are checked before any window is opened
    monkeypatch.setattr("app.display_check.display_problem", lambda *a, **k: None)
    opened = []
    monkeypatch.setattr(app.launching, "launch", lambda *a, **k: opened.append((a, k)) or 0)
    assert run_explore(["--preset", "small", "--kinematics", "calibrated"]) == 0
    assert opened == [((None,), {"preset": "small", "session": None, "restore": None, "kinematics": "calibrated",
                                 "notes": []})]
    mfile = small_manifold.save(tmp_path / "m.npz")
    with pytest.raises(CliError, match=r"--kinematics chooses the synthetic talker's; .*m\.npz.*leave it out"):
        run_explore([str(mfile), "--kinematics", "calibrated"])
    assert len(opened) == 1  # refused: no window
    assert run_explore([str(mfile)]) == 0 and opened[-1][1]["kinematics"] == "classic"


def test_explore_refusal_through_the_command_line(monkeypatch, tmp_path, capsys, small_manifold):
    from app.cli import main

    monkeypatch.setenv("DISPLAY", ":0")
    mfile = small_manifold.save(tmp_path / "m.npz")
    assert main(["explore", str(mfile), "--kinematics", "calibrated"]) == 2
    assert "--kinematics chooses the synthetic talker's" in capsys.readouterr().err


def test_a_missing_file_is_said_before_the_missing_display(no_display):
    with pytest.raises(CliError, match="m.npz: no such file"):
        run_explore(["m.npz", "--session", "s.json"])

"""The calibrated synthetic talker from the window's File menu and from ``lipspace explore``:
it opens, the window says which talker it shows, and sessions and autosaves keep it (needs a
display: Xvfb is started if absent). The small talker keeps each load to seconds."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

pytestmark = pytest.mark.gui

CALIBRATED = "calibrated on articulograph lips"


@pytest.fixture(scope="module")
def talker_cache(tmp_path_factory, small_manifold):
    """A cache folder of this module's own, holding the classic small talker's manifold (so
    the classic talker opens from it); the calibrated one is built by the first test that opens it."""
    from app.files.source_loading import cached_manifold_path

    folder = tmp_path_factory.mktemp("talker-cache")
    old = os.environ.get("LIPSPACE_CACHE_DIR")
    os.environ["LIPSPACE_CACHE_DIR"] = str(folder)
    small_manifold.save(cached_manifold_path("small"))
    yield folder
    if old is None:
        os.environ.pop("LIPSPACE_CACHE_DIR", None)
    else:
        os.environ["LIPSPACE_CACHE_DIR"] = old


@pytest.fixture
def win(qapp, small_manifold, tmp_path, talker_cache):
    from PySide6 import QtCore

    from app.main_window import MainWindow
    from app.window_settings import WindowSettings

    settings = WindowSettings(QtCore.QSettings(str(tmp_path / "s.ini"), QtCore.QSettings.Format.IniFormat))
    w = MainWindow(small_manifold, source={"path": None, "preset": "small"}, settings=settings)
    w.show()
    for _ in range(5):
        qapp.processEvents()
    yield w
    if w._runner is not None:
        w._runner.cancel()
    w.close()


def _wait(qtbot, runner):
    qtbot.waitUntil(lambda: runner.state != "running", timeout=120000)
    assert runner.state == "done", runner.state


def _is_calibrated(manifold) -> bool:
    """Only the calibrated talker moves the jaw forward (the classic's control stays 0)."""
    return float(np.ptp(manifold.corpus_.latent["jaw_forward"])) > 0.5


def test_the_file_menu_opens_the_calibrated_talker(win, qtbot):
    menu = next(a.menu() for a in win.menuBar().actions()[0].menu().actions()
                if a.menu() is not None and a.text() == "Open synthetic talker")
    texts = [a.text() for a in menu.actions()]
    assert texts == ["small", "default", "paper", "", f"small, {CALIBRATED}", f"default, {CALIBRATED}"]
    assert "articulograph sensors" in win.synthetic_actions["default", "calibrated"].toolTip()
    assert "synthetic talker (small)" in win.windowTitle() and not _is_calibrated(win.state.manifold)

    win.synthetic_actions["small", "calibrated"].trigger()
    runner = win._runner
    assert CALIBRATED in win.statusBar().currentMessage()  # "loading the synthetic talker (small, calibrated ...)"
    _wait(qtbot, runner)
    s = win.state
    assert s.source == {"path": None, "preset": "small", "kind": "synthetic", "kinematics": "calibrated"}
    assert _is_calibrated(s.manifold)
    assert win.windowTitle() == f"Lipspace — synthetic talker (small, {CALIBRATED})"

    win.synthetic_actions["small", "classic"].trigger()  # and back: the classic talker, from its cache
    _wait(qtbot, win._runner)
    assert s.source["kinematics"] == "classic" and not _is_calibrated(s.manifold)
    assert win.windowTitle() == "Lipspace — synthetic talker (small)"


def test_sessions_reopen_the_talker_they_were_saved_with(win, qtbot, tmp_path):
    s = win.state
    win.synthetic_actions["small", "calibrated"].trigger()
    _wait(qtbot, win._runner)
    s.select_frame(40)
    saved = win.save_session(tmp_path / "cal.lipspace.json")
    assert json.loads(saved.read_text())["source"]["kinematics"] == "calibrated"

    win.synthetic_actions["small", "classic"].trigger()
    _wait(qtbot, win._runner)
    assert s.source["kinematics"] == "classic"
    runner = win.open_session(saved)  # another talker than the one shown: reloaded, then restored
    assert runner is not None
    _wait(qtbot, runner)
    qtbot.waitUntil(lambda: s.frame == 40, timeout=10000)
    assert s.source["kinematics"] == "calibrated" and _is_calibrated(s.manifold)
    assert CALIBRATED in win.windowTitle()

    # a session written before the talker had kinematics (no key) opens the classic talker
    old = tmp_path / "old.lipspace.json"
    old.write_text(json.dumps({"lipspace_session": 2, "source": {"path": None, "preset": "small"},
                               "selection": {"frame": 25, "state": None, "target": None}}))
    runner = win.open_session(old)
    assert runner is not None  # the calibrated talker is shown: the classic one is loaded
    _wait(qtbot, runner)
    qtbot.waitUntil(lambda: s.frame == 25, timeout=10000)
    assert s.source.get("kinematics") == "classic" and not _is_calibrated(s.manifold)
    assert win.windowTitle() == "Lipspace — synthetic talker (small)"
    assert win.open_session(old) is None  # the same talker: only the selection is restored, nothing reloaded


@pytest.mark.parametrize("how", ["--kinematics", "autosave"])
def test_explore_opens_the_calibrated_talker(talker_cache, tmp_path, monkeypatch, how, dead_pid, run_cli_window):
    """``lipspace explore --preset small --kinematics calibrated`` opens it; so does
    ``lipspace explore --restore`` of a crashed run that showed it."""
    from app.files.autosave import Autosaver

    monkeypatch.setenv("LIPSPACE_STATE_DIR", str(tmp_path / "state"))
    if how == "autosave":
        dead = Autosaver(pid=dead_pid())
        dead.begin()
        src = {"path": None, "preset": "small", "kind": "synthetic", "kinematics": "calibrated"}
        dead.save(lambda p: p.write_text(json.dumps({"lipspace_session": 2, "source": src, "selection": {
            "frame": 33, "state": None, "target": None}})))
        argv = ["explore", "--restore"]
    else:
        argv = ["explore", "--preset", "small", "--kinematics", "calibrated", "--no-restore"]
    code, seen = run_cli_window(
        argv, ready=lambda w: w.state.manifold is not None and (how != "autosave" or w.state.frame is not None),
        look=lambda w: {"source": dict(w.state.source), "title": w.windowTitle(), "frame": w.state.frame,
                        "calibrated": _is_calibrated(w.state.manifold)},
        timeout_s=120.0)
    assert code == 0 and seen is not None
    assert seen["source"] == {"path": None, "preset": "small", "kind": "synthetic", "kinematics": "calibrated"}
    assert seen["calibrated"] and seen["title"] == f"Lipspace — synthetic talker (small, {CALIBRATED})"
    assert seen["frame"] == (33 if how == "autosave" else None)

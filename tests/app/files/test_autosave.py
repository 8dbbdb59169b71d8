"""Autosave: debounced saving, abnormal-exit detection and restore (Qt-free, then the window)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from app.files.autosave import Autosaver, Recovery, pid_alive, resolve_recovery, session_fingerprint, state_dir
from app.files.session import SessionError, load_session

REPO = Path(__file__).resolve().parents[3]


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def _session_json(frame: int, source: dict | None = None) -> str:
    return json.dumps({"lipspace_session": 2, "source": source or {"path": None, "preset": "small"},
                       "selection": {"frame": frame, "state": None, "target": None}}) + "\n"


def test_saves_once_the_session_stays_unchanged_for_the_delay(tmp_path):
    clock = Clock()
    a = Autosaver(tmp_path, delay=3.0, clock=clock)
    writes = []

    def write(p):
        writes.append(clock.t)
        p.write_text("x")

    assert not a.tick(None, write)  # nothing loaded yet: nothing to save
    for k in range(5):  # a change every second: no save while the user keeps changing things
        assert not a.tick(("state", k), write)
        clock.t += 1.0
    assert writes == []
    clock.t += 1.9
    assert not a.tick(("state", 4), write)  # 2.9 s after the last change
    clock.t += 0.1
    assert a.tick(("state", 4), write) and writes == [clock.t]  # 3 s after it: saved, once
    clock.t += 10
    assert not a.tick(("state", 4), write) and len(writes) == 1  # unchanged: never saved again
    assert not a.tick(("state", 5), write)
    clock.t += 3
    assert a.tick(("state", 5), write) and a.saves == 2
    with pytest.raises(ValueError, match=">= 0 seconds"):
        Autosaver(tmp_path, delay=-1)
    with pytest.raises(ValueError, match="max_delay must be >= delay"):
        Autosaver(tmp_path, delay=5, max_delay=1)


def test_a_session_that_keeps_changing_is_still_saved(tmp_path):
    clock = Clock()
    a = Autosaver(tmp_path, delay=3.0, max_delay=30.0, clock=clock)
    writes = []
    for k in range(70):  # a click every second for 70 s: never 3 s of quiet
        if a.tick(("click", k), lambda p: writes.append(clock.t)):
            pass
        clock.t += 1.0
    assert writes == [130.0, 161.0]  # 30 s after the first unsaved change, then again


def test_a_failed_write_is_reported_not_raised(tmp_path):
    clock = Clock()
    a = Autosaver(tmp_path, delay=0, clock=clock)

    def full(_p):
        raise OSError(28, "No space left on device")

    assert not a.tick("s1", full)
    assert "No space left" in a.last_error and not a.dirty
    assert a.tick("s2", lambda p: p.write_text("x")) and a.last_error is None


def test_state_dir_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("LIPSPACE_STATE_DIR", str(tmp_path / "st"))
    assert state_dir() == tmp_path / "st"
    assert Autosaver().directory == tmp_path / "st" / "autosave"


def test_crashed_run_is_detected_and_its_autosave_restored(tmp_path):
    """A real process writes its marker and an autosave, then aborts (as on none_dealloc)."""
    code = textwrap.dedent(f"""
        import os, sys
        sys.path.insert(0, {str(REPO)!r})
        from app.files.autosave import Autosaver
        from engine.files.atomic import write_text_atomic
        a = Autosaver({str(tmp_path)!r})
        assert a.begin() is None
        a.save(lambda p: write_text_atomic(p, {_session_json(41)!r}))
        os.abort()
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode != 0, proc.stderr  # it died
    a = Autosaver(tmp_path)
    rec = a.begin()
    assert isinstance(rec, Recovery) and rec.session.name.startswith("autosave-") and rec.pid != os.getpid()
    assert "did not exit normally" in rec.describe()
    d = resolve_recovery(a, rec, restore=True)
    assert d["selection"]["frame"] == 41
    assert rec.session.exists() and rec.marker.exists()  # kept until this run has autosaved
    a.save(lambda p: p.write_text(_session_json(42)))
    assert not rec.session.exists() and not rec.marker.exists()
    a.finish()  # a clean exit leaves nothing to offer
    assert list(tmp_path.iterdir()) == []
    assert Autosaver(tmp_path).begin() is None


def test_running_and_cleanly_closed_runs_are_not_offered(tmp_path, dead_pid):
    live = Autosaver(tmp_path, pid=os.getppid())  # another explorer that is still running
    live.begin()
    live.save(lambda p: p.write_text(_session_json(1)))
    clean = Autosaver(tmp_path, pid=dead_pid())
    clean.begin()
    clean.save(lambda p: p.write_text(_session_json(2)))
    clean.finish()
    nosave = Autosaver(tmp_path, pid=dead_pid())  # crashed before its first autosave
    nosave.begin()
    me = Autosaver(tmp_path)
    assert me.begin() is None
    assert live.marker.exists() and live.session.exists()  # untouched
    assert not nosave.marker.exists()  # its stale marker is tidied away
    assert pid_alive(os.getpid()) and not pid_alive(dead_pid())
    if sys.platform.startswith("linux"):  # a reused pid is told apart by its start time
        assert not pid_alive(os.getpid(), start_ticks=1)


def test_a_crashed_run_with_our_own_pid_is_still_offered(tmp_path):
    """After a reboot the new explorer may get the crashed one's pid: its autosave must survive."""
    old = Autosaver(tmp_path, pid=os.getpid())
    old.begin()
    old.save(lambda p: p.write_text(_session_json(5)))
    old.marker.write_text(json.dumps({"pid": os.getpid(), "started": 0.0, "start_ticks": None}))
    time.sleep(0.002)  # the new run starts later
    new = Autosaver(tmp_path)
    assert new.pid == old.pid
    rec = new.begin()
    assert rec is not None and rec.session == old.session and new.session != old.session


def test_restore_choices(tmp_path, dead_pid):
    def crashed(frame):
        dead = Autosaver(tmp_path, pid=dead_pid())
        dead.begin()
        dead.save(lambda p: p.write_text(_session_json(frame)))
        return dead

    dead = crashed(7)
    me = Autosaver(tmp_path)
    rec = me.begin()
    assert rec.pid == dead.pid
    assert resolve_recovery(me, rec, restore=False) is None and rec.session.exists()  # --no-restore: kept
    assert resolve_recovery(me, rec, restore=None) is None and rec.session.exists()  # no dialog: later
    asked = []
    assert resolve_recovery(me, rec, restore=None, ask=lambda r: asked.append(r) or "discard") is None
    assert asked == [rec] and not rec.session.exists() and not rec.marker.exists()
    rec2 = Autosaver(tmp_path, pid=dead_pid())
    rec2.begin()
    rec2.save(lambda p: p.write_text("{damaged"))
    r = Autosaver(tmp_path).begin()
    with pytest.raises(SessionError, match="could not be restored.*not a readable.*it was moved to .*damaged"):
        resolve_recovery(me, r, restore=None, ask=lambda _r: "restore")
    assert not r.session.exists()  # not offered again, but kept for a look
    assert [p.name.split(".lipspace.json")[0] for p in (tmp_path / "damaged").glob("autosave-*")] == [
        r.session.name.split(".lipspace.json")[0]]
    with pytest.raises(ValueError, match="must answer"):
        resolve_recovery(me, Recovery(r.session, r.marker, 1, 0.0, 0.0), restore=None, ask=lambda _r: "yes")


def test_fingerprint_changes_with_everything_saved(app_manifold):
    from dataclasses import replace

    from app.models.state import AppState, TrajectoryData

    s = AppState()
    assert session_fingerprint(s) is None
    s = AppState(app_manifold)
    fps = [session_fingerprint(s)]
    s.select_frame(10)
    fps.append(session_fingerprint(s))
    fps.append(session_fingerprint(s, cameras={"manifold": [[1, 2, 3], [0, 0, 0], [0, 0, 1]]}))
    s.set_trajectories(synthetic=TrajectoryData(Y=app_manifold.Fy_[:5]))
    fps.append(session_fingerprint(s))
    from engine.phonetics.targets import targets_from_utterance

    tg = targets_from_utterance(app_manifold, app_manifold.corpus_.utterances[0].id, on_collision="merge")
    fps.append(session_fingerprint(s, targets=tg))
    fps.append(session_fingerprint(s, targets=replace(tg)))  # a dragged copy
    assert len(set(fps)) == len(fps)
    s.set_playback(2)  # playing is not part of the session
    assert session_fingerprint(s, targets=tg) == fps[-2]


# ============================================================================ the window
@pytest.mark.gui
def test_window_autosaves_and_restores_targets_trajectory_and_camera(qapp, qtbot, app_manifold, tmp_path):
    from app.main_window import MainWindow
    from app.models.state import TrajectoryData
    from engine.phonetics.targets import targets_from_utterance

    m = app_manifold
    a = Autosaver(tmp_path, delay=0.5)
    a.begin()
    win = MainWindow(m, source={"path": None, "preset": "small"}, autosave=a)
    qtbot.addWidget(win)
    s = win.state
    u = m.corpus_.utterances[1]
    s.set_utterance(u.id)
    s.select_frame(u.start + 5)
    syn = TrajectoryData(Y=m.Fy_[u.start:u.stop] * 1.01, Fx=m.Fx_[u.start:u.stop], label="linear", rate=m.corpus_.rate)
    s.set_trajectories(synthetic=syn)
    tg = targets_from_utterance(m, u.id, on_collision="merge")
    win.editor.targets = tg
    cam = [[5.0, 4.0, 3.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    win.manifold_view.set_camera(cam)
    qtbot.waitUntil(lambda: a.saves >= 1 and not a.dirty, timeout=15000)
    d = load_session(a.session)
    assert d["selection"]["frame"] == u.start + 5 and d["utterance"] == u.id
    np.testing.assert_allclose(d["cameras"]["manifold"][0], cam[0], rtol=1e-6)
    np.testing.assert_array_equal(d["_synthetic"].Y, np.asarray(syn.Y, np.float32))
    assert d["_targets"] == tg
    saves = a.saves
    qtbot.wait(1500)
    assert a.saves == saves  # nothing changed: nothing written
    # restore into a cleared window: the same selection, trajectory, targets and camera
    s.set_utterance(None)
    s.clear_selection()
    win.editor.targets = None
    win.manifold_view.set_camera([[9.0, 9.0, 9.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    win.apply_session(d)
    assert s.frame == u.start + 5 and s.utterance == u.id and len(s.synthetic) == len(syn)
    assert win.editor.targets == tg and win.editor.timeline.targets == tg
    np.testing.assert_allclose(win.manifold_view.camera()[0], cam[0], rtol=1e-6)
    win.close()
    a.finish()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.gui
@pytest.mark.parametrize("how", ["--restore", "dialog"])
def test_explore_restores_a_crashed_session(app_manifold, tmp_path, monkeypatch, how, dead_pid, run_cli_window):
    """After a crash, ``lipspace explore --restore`` (or the dialog's Restore button) loads the
    autosave's source and applies the session."""
    from PySide6 import QtWidgets

    mfile = app_manifold.save(tmp_path / "m.npz")
    monkeypatch.setenv("LIPSPACE_STATE_DIR", str(tmp_path / "state"))
    dead = Autosaver(pid=dead_pid())
    dead.begin()
    dead.save(lambda p: p.write_text(_session_json(33, {"path": str(mfile), "preset": "default"})))
    questions = []

    def answer():
        for box in QtWidgets.QApplication.topLevelWidgets():
            if isinstance(box, QtWidgets.QMessageBox) and box.isVisible():  # the restore question
                questions.append(box.text())
                next(b for b in box.buttons() if b.text() == "Restore").click()

    code, seen = run_cli_window(
        ["explore"] + (["--restore"] if how == "--restore" else []),
        ready=lambda w: w.autosaver is not None and w.state.frame is not None,
        look=lambda w: {"frame": w.state.frame, "path": w.state.source.get("path"),
                        "marker": w.autosaver.marker.exists()},
        each=answer)
    assert code == 0
    if how == "--restore":
        assert questions == []  # no dialog
    else:
        assert "did not exit normally" in questions[0] and f"process {dead.pid}" in questions[0]
    assert seen == {"frame": 33, "path": str(mfile.resolve()), "marker": True}
    assert not (tmp_path / "state" / "autosave").exists() or list((tmp_path / "state" / "autosave").iterdir()) == []

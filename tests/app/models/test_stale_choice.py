"""A manifold file whose stored synthesis choice other code measured (an older Lipspace) is said, with
what it costs and how to store a current one: on the command line before a synthesis that reads the
choice, in the window's status bar once the file is shown."""
from __future__ import annotations

import copy
import types

import pytest

from app.models.trajectories import needs_choice, stale_choice_note
from engine.synthesis.stored_choice import choice_code


def _with_choice(manifold, code):
    m = copy.copy(manifold)  # the shared fixture stays as it is
    m.synthesis_choice_ = None if code is None else {"best": {"states": "manifold"}, "blend": 0.5, "code": code}
    return m


def test_only_a_choice_other_code_measured_is_said(app_manifold):
    note = stale_choice_note(_with_choice(app_manifold, "0123abcd"), "talk.npz")
    assert note.startswith("talk.npz stores a synthesis choice that other code measured")
    assert "lipspace build" in note and "fitted anew each time" in note
    assert stale_choice_note(_with_choice(app_manifold, choice_code()), "talk.npz") is None  # current: nothing
    assert stale_choice_note(_with_choice(app_manifold, None), "talk.npz") is None  # none stored: measured, cached


def test_methods_that_read_the_choice():
    assert needs_choice("best") and needs_choice("manifold") and needs_choice("sliding-window")
    assert not needs_choice("viterbi") and not needs_choice("linear")


def test_the_command_line_says_it_once_and_not_when_quiet(app_manifold, capsys):
    from app.cli.synthesis_steps import note_stale_choice

    stale = _with_choice(app_manifold, "0123abcd")
    args = types.SimpleNamespace(quiet=False, method="best", manifold="/data/talk.npz")
    note_stale_choice(args, stale)
    note_stale_choice(args, stale)
    err = capsys.readouterr().err
    assert err.count("lipspace synthesize: note: talk.npz stores a synthesis choice") == 1
    for args in (types.SimpleNamespace(quiet=True, method="best", manifold="/data/talk.npz"),
                 types.SimpleNamespace(quiet=False, method="viterbi", manifold="/data/talk.npz")):
        note_stale_choice(args, stale)
    note_stale_choice(types.SimpleNamespace(quiet=False, method="best", manifold="/data/talk.npz"),
                      _with_choice(app_manifold, choice_code()))
    assert capsys.readouterr().err == ""


@pytest.mark.gui
def test_the_window_says_it_in_the_status_bar(qapp, qtbot, app_manifold, tmp_path):
    from app.main_window import MainWindow

    path = tmp_path / "older.npz"
    _with_choice(app_manifold, "0123abcd").save(path)
    w = MainWindow()
    try:
        runner = w.open_source(str(path))
        qtbot.waitUntil(lambda: runner.state != "running", timeout=60000)
        assert runner.state == "done"
        shown = w.statusBar().currentMessage()
        assert shown == "older.npz: synthesis choice from older code: rebuild with 'lipspace build'"
    finally:
        w.close()

"""Hostile session files opened in the window (issue 16): a dialog in plain language, never
a traceback on stderr while the window shows nothing, never the content of a file the
session points at (``/etc/passwd``), and the window keeps what it showed."""
from __future__ import annotations

import inspect
import json

import pytest

pytestmark = pytest.mark.gui


@pytest.fixture
def window(qapp, qtbot, small_manifold, tmp_path, monkeypatch):
    from PySide6 import QtCore, QtWidgets

    from app.main_window import MainWindow

    shown = []
    monkeypatch.setattr(QtWidgets.QMessageBox, "critical", lambda parent, title, text, *a, **k: shown.append(text))
    kw = {}
    if "settings" in inspect.signature(MainWindow).parameters:
        from app.window_settings import WindowSettings

        kw["settings"] = WindowSettings(QtCore.QSettings(str(tmp_path / "s.ini"), QtCore.QSettings.Format.IniFormat))
    w = MainWindow(small_manifold, **kw)
    w.show()
    w.shown_errors = lambda: shown + ([w.last_error_message] if getattr(w, "last_error_message", None) else [])
    yield w
    for box in w.findChildren(QtWidgets.QMessageBox):
        box.close()
    w.close()


def _open(window, qtbot, monkeypatch, path):
    from PySide6 import QtWidgets

    monkeypatch.setattr(QtWidgets.QFileDialog, "getOpenFileName", lambda *a, **k: (str(path), ""))
    window.open_session_dialog()
    runner = getattr(window, "_runner", None)
    if runner is not None and runner.state == "running":
        qtbot.waitUntil(lambda: runner.state != "running", timeout=60000)
    qtbot.waitUntil(lambda: bool(window.shown_errors()), timeout=10000)
    return window.shown_errors()


@pytest.mark.parametrize("source", ["/etc/passwd", "../../../../../../../../etc/passwd", ["a.npz"]],
                         ids=["absolute", "relative", "a-list"])
def test_session_pointing_at_a_system_file_or_the_wrong_type_gets_a_dialog(window, qtbot, monkeypatch, tmp_path,
                                                                          capfd, source):
    s = tmp_path / "s.lipspace.json"
    s.write_text(json.dumps({"lipspace_session": 1, "source": {"path": source}}))
    fy = window.state.manifold.Fy_
    errors = _open(window, qtbot, monkeypatch, s)
    text = " ".join(errors)
    assert "s.lipspace.json" in text and "root:" not in text and "Traceback" not in text, text
    assert window.state.manifold.Fy_ is fy  # nothing was opened
    assert "Traceback" not in capfd.readouterr().err


def test_session_nested_too_deeply_gets_a_dialog(window, qtbot, monkeypatch, tmp_path, capfd):
    s = tmp_path / "deep.lipspace.json"
    s.write_text('{"lipspace_session": 1, "x": ' + "[" * 100_000 + "]" * 100_000 + "}")
    text = " ".join(_open(window, qtbot, monkeypatch, s))
    assert "deep.lipspace.json" in text and "Traceback" not in capfd.readouterr().err


@pytest.mark.parametrize("selection", [{"frame": 10**9}, {"state": 10**6}])
def test_session_indices_out_of_range_for_the_loaded_manifold_get_a_dialog(window, qtbot, monkeypatch, tmp_path,
                                                                           capfd, small_manifold, selection):
    m = small_manifold.save(tmp_path / "m.npz")
    s = tmp_path / "range.lipspace.json"
    s.write_text(json.dumps({"lipspace_session": 1, "source": {"path": str(m)}, "selection": selection}))
    text = " ".join(_open(window, qtbot, monkeypatch, s))
    assert "range.lipspace.json" in text or "does not fit" in text, text
    assert "Traceback" not in capfd.readouterr().err

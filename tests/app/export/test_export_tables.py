"""File › Export frame table and File › Export TextGrids: what ``lipspace table`` writes, from the window."""
from __future__ import annotations

import pytest

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def window(qapp, app_manifold, main_window_factory):
    with main_window_factory(qapp, app_manifold) as w:
        yield w


def _action(win, text):
    menu = win.menuBar().actions()[0].menu()
    return next(a for a in menu.actions() if a.text().replace("&", "").startswith(text))


def test_the_frame_table_from_the_menu_is_the_command_lines(window, qtbot, tmp_path, monkeypatch, app_manifold):
    from PySide6 import QtWidgets

    from app.cli import main

    out = tmp_path / "frames.csv"
    monkeypatch.setattr(QtWidgets.QFileDialog, "getSaveFileName", lambda *a, **k: (str(out), "CSV table (*.csv)"))
    _action(window, "Export frame table").trigger()
    qtbot.waitUntil(lambda: (tmp_path / "frames.csv.json").exists() and out.exists(), timeout=30000)
    qtbot.waitUntil(lambda: "wrote" in window.statusBar().currentMessage(), timeout=5000)
    mfile = app_manifold.save(tmp_path / "m.npz")
    assert main(["table", str(mfile), "-o", str(tmp_path / "cli.csv")]) == 0
    assert out.read_bytes() == (tmp_path / "cli.csv").read_bytes()


def test_textgrids_from_the_menu_ask_before_replacing(window, qtbot, tmp_path, monkeypatch, app_manifold):
    from PySide6 import QtWidgets

    monkeypatch.setattr(QtWidgets.QFileDialog, "getExistingDirectory", lambda *a, **k: str(tmp_path))
    _action(window, "Export TextGrids").trigger()
    n = len(app_manifold.corpus_.utterances)
    qtbot.waitUntil(lambda: len(list(tmp_path.glob("*.TextGrid"))) == n, timeout=30000)
    qtbot.waitUntil(lambda: f"wrote {n} TextGrids" in window.statusBar().currentMessage(), timeout=5000)
    first = tmp_path / f"{app_manifold.corpus_.utterances[0].id}.TextGrid"
    first.write_text("edited in Praat")
    asked = []
    No, Yes = QtWidgets.QMessageBox.StandardButton.No, QtWidgets.QMessageBox.StandardButton.Yes
    monkeypatch.setattr(QtWidgets.QMessageBox, "question", lambda *a, **k: asked.append(a[2]) or No)
    _action(window, "Export TextGrids").trigger()
    assert asked and f"{n} of the TextGrids exist already" in asked[0] and first.read_text() == "edited in Praat"
    monkeypatch.setattr(QtWidgets.QMessageBox, "question", lambda *a, **k: Yes)
    window.statusBar().clearMessage()
    _action(window, "Export TextGrids").trigger()
    qtbot.waitUntil(lambda: f"wrote {n} TextGrids" in window.statusBar().currentMessage(), timeout=30000)
    assert first.read_text().startswith('File type = "ooTextFile"')


def test_the_table_filters_are_the_writers_suffixes():
    from app.export.tables import table_filters
    from app.figures.export import filter_suffixes
    from engine.io.writers.tidy import TABLE_SUFFIXES, have_parquet

    assert filter_suffixes(table_filters()) == (TABLE_SUFFIXES if have_parquet() else (".csv",))

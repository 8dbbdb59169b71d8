"""The main window: remembered geometry and layout, Reset layout, recent files, a minimum size at which no
dock collapses, the user guide, the shortcut sheet, About, sessions that keep the editor's work, and a
quiet console (needs a display: Xvfb is started if absent)."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

pytestmark = pytest.mark.gui


def _settings(path):
    from PySide6 import QtCore

    from app.window_settings import WindowSettings

    return WindowSettings(QtCore.QSettings(str(path), QtCore.QSettings.Format.IniFormat))


def _window(qapp, settings, manifold=None):
    from app.main_window import MainWindow

    w = MainWindow(manifold, source={"path": None, "preset": "small"} if manifold is not None else None,
                   settings=settings)
    w.show()
    for _ in range(5):
        qapp.processEvents()
    return w


def test_geometry_and_dock_layout_are_remembered(qapp, tmp_path):
    from PySide6 import QtCore

    ini = tmp_path / "lipspace.ini"
    w1 = _window(qapp, _settings(ini))
    assert not w1.layout_restored  # nothing saved yet
    size = (w1.minimumWidth() + 57, w1.minimumHeight() + 111)
    w1.resize(*size)
    w1.docks["clusters"].close()
    w1.addDockWidget(QtCore.Qt.DockWidgetArea.LeftDockWidgetArea, w1.docks["lips"])
    qapp.processEvents()
    w1.close()
    assert ini.is_file()

    w2 = _window(qapp, _settings(ini))
    try:
        assert w2.layout_restored
        assert (w2.width(), w2.height()) == size
        assert w2.docks["clusters"].isHidden() and not w2.docks["scree"].isHidden()
        assert w2.dockWidgetArea(w2.docks["lips"]) == QtCore.Qt.DockWidgetArea.LeftDockWidgetArea
        # View > Reset layout: every dock back where it started, shown (the small multiples start hidden)
        reset = next(a for a in w2.menuBar().actions()[2].menu().actions() if a.text() == "Reset &layout")
        reset.trigger()
        qapp.processEvents()
        assert all(not d.isHidden() and not d.isFloating() for k, d in w2.docks.items() if k != "multiples")
        assert w2.docks["multiples"].isHidden()
        assert w2.dockWidgetArea(w2.docks["lips"]) == QtCore.Qt.DockWidgetArea.RightDockWidgetArea
        assert w2.dockWidgetArea(w2.docks["editor"]) == QtCore.Qt.DockWidgetArea.BottomDockWidgetArea
        assert w2.docks["scree"] in w2.tabifiedDockWidgets(w2.docks["clusters"])
    finally:
        w2.close()


def test_a_layout_saved_over_other_docks_is_not_restored(qapp, tmp_path):
    """A layout saved by a release with other docks (before the small multiples and the Compare panel
    existed) is left alone: restored, it showed the small multiples as an empty box under the clusters."""
    from PySide6 import QtCore

    ini = tmp_path / "lipspace.ini"
    w1 = _window(qapp, _settings(ini))
    w1.docks["multiples"].show()  # as the old release left it
    qapp.processEvents()
    w1.close()
    raw = QtCore.QSettings(str(ini), QtCore.QSettings.Format.IniFormat)
    assert raw.value("window/docks").split() == sorted(f"dock_{k}" for k in w1.docks)
    raw.setValue("window/docks", "dock_clusters dock_editor dock_lips dock_scree")
    raw.sync()

    w2 = _window(qapp, _settings(ini))
    try:
        assert not w2.layout_restored
        assert w2.docks["multiples"].isHidden()
    finally:
        w2.close()
    w3 = _window(qapp, _settings(ini))  # saved again by w2 over the docks it has: restored
    try:
        assert w3.layout_restored
    finally:
        w3.close()


@pytest.mark.parametrize("size", [(1600, 1000), (1280, 720)])
def test_a_first_window_draws_no_tab_of_a_hidden_dock(qapp, tmp_path, app_manifold, size, tab_bar_probe):
    """A new window (nothing saved) shows the small multiples nowhere, not even as a stray tab."""
    from PySide6 import QtWidgets

    w = _window(qapp, _settings(tmp_path / "s.ini"), app_manifold)
    try:
        w.resize(*size)
        for _ in range(10):
            qapp.processEvents()
        assert w.docks["multiples"].isHidden()
        tab_bar_probe(w)
        names = [[t.tabText(i) for i in range(t.count())] for t in w.findChildren(QtWidgets.QTabBar)
                 if t.isVisible() and t.geometry().intersects(w.rect())]
        assert all("Small multiples" not in n for n in names), names
    finally:
        w.close()


def test_the_scree_plot_is_made_when_its_tab_is_raised(qapp, tmp_path, app_manifold):
    """The scree panel starts behind the clusters table without its plot; raising its tab draws it."""
    w = _window(qapp, _settings(tmp_path / "s.ini"), app_manifold)
    try:
        assert w.scree.canvas is None and w.docks["clusters"].isVisible()
        w.docks["scree"].raise_()
        for _ in range(5):
            qapp.processEvents()
        assert w.scree.canvas is not None and w.scree.canvas.isVisible()
        assert len(w.scree.figure.axes[0].get_lines()) == 2
    finally:
        w.close()


def test_at_its_minimum_size_every_dock_keeps_a_usable_size(qapp, app_manifold, tmp_path):
    w = _window(qapp, _settings(tmp_path / "s.ini"), app_manifold)
    try:
        w.resize(1179, 407)  # where the Lips dock used to vanish
        qapp.processEvents()
        w.resize(1, 1)
        for _ in range(5):
            qapp.processEvents()
        mn = w.minimumSize()
        assert (w.width(), w.height()) == (mn.width(), mn.height())
        assert mn.width() <= 1600 and mn.height() <= 1000  # still fits an ordinary screen
        tabbed = [k for k in ("clusters", "scree", "compare") if k in w.docks]
        for key in tabbed:  # the tabbed docks: each in turn
            w.docks[key].raise_()
            for _ in range(3):
                qapp.processEvents()
            for k, dock in w.docks.items():
                if (k in tabbed and k != key) or k == "multiples":  # the small multiples start hidden
                    continue
                view = dock.widget()
                assert dock.isVisible() and view.isVisible(), k
                assert view.width() >= view.minimumWidth() > 0 and view.height() >= view.minimumHeight() > 0, k
        mv = w.manifold_view
        assert mv.width() >= mv.minimumWidth() > 0 and mv.height() >= mv.minimumHeight() > 0
        assert w.editor.timeline.isVisible() and w.editor.synth_btn.isVisible()
    finally:
        w.close()


def test_recent_files_list_opened_files_and_drop_missing_ones(qapp, qtbot, tmp_path, manifold_file):
    from app.window_settings import MAX_RECENT

    settings = _settings(tmp_path / "s.ini")
    w = _window(qapp, settings)
    try:
        assert [a.isEnabled() for a in w.recent_menu.actions()] == [False]  # "(no recent files)"
        runner = w.open_source(str(manifold_file))
        qtbot.waitUntil(lambda: runner.state != "running", timeout=60000)
        assert runner.state == "done" and w.state.manifold is not None
        assert settings.recent_files() == [str(manifold_file.resolve())]
        w.recent_menu.aboutToShow.emit()
        first = w.recent_menu.actions()[0]
        assert first.data() == str(manifold_file.resolve()) and manifold_file.name in first.text()
        gone = tmp_path / "gone.npz"
        settings.add_recent(gone)
        for i in range(MAX_RECENT + 3):
            settings.add_recent(tmp_path / f"f{i}.npz")
        assert len(settings.recent_files()) == MAX_RECENT
        assert w.open_recent(str(gone)) is None
        assert str(gone.resolve()) not in settings.recent_files()
        assert "no longer there" in w.last_error_message
    finally:
        w.close()


def test_user_guide_shortcut_sheet_and_about(qapp, tmp_path):
    from PySide6 import QtGui

    from app.help import CITATION, SHORTCUTS
    from engine import __version__

    w = _window(qapp, _settings(tmp_path / "s.ini"))
    try:
        help_menu = w.menuBar().actions()[-1].menu()
        guide = next(a for a in help_menu.actions() if a.text() == "&User guide")
        assert guide.shortcut() == QtGui.QKeySequence(QtGui.QKeySequence.StandardKey.HelpContents)
        guide.trigger()
        page = w._help.browser.toPlainText()
        assert w._help.isVisible() and "Lipspace user guide" in page
        for words in ("Trajectory editor", "Undo", "Reset layout", "Citing the method"):
            assert words in page
        assert not w._help.browser.openExternalLinks()
        next(a for a in help_menu.actions() if a.text() == "&Keyboard shortcuts").trigger()
        sheet = w._help.browser.toPlainText()
        assert all(keys in sheet and what in sheet for keys, _where, what in SHORTCUTS)
        # each window shortcut of the sheet is really bound to an action of the window
        bound = {k.toString() for a in w.findChildren(QtGui.QAction) for k in a.shortcuts()}
        for keys, where, _what in SHORTCUTS:
            if where == "window":
                assert keys in bound, keys
        add_state_key = next(k for k, _w, t in SHORTCUTS if "Add the selected state" in t)
        assert w.editor.add_state_btn.shortcut().toString() == add_state_key
        # the editor's keys are bound where the sheet says
        assert {"Space", "Tab", "Shift+Tab"} <= set(w.editor.key_shortcuts)
        assert w.frame_action.shortcut().toString() == "F"
        # docs/USER_GUIDE.md's keyboard table says what the sheet says, row for row
        from pathlib import Path

        guide = (Path(__file__).resolve().parents[2] / "docs" / "USER_GUIDE.md").read_text(encoding="utf-8")
        table = guide[guide.index("| keys | where | what |"):].split("\n\n")[0].splitlines()[2:]
        rows = [tuple(c.strip() for c in line.strip("|").split("|")) for line in table]
        assert [(k, where, what.lower()) for k, where, what in rows] == \
            [(k, where, what.lower()) for k, where, what in SHORTCUTS]
        about = w.about_text()
        assert __version__ in about and "Edge" in about and "Hilton" in about and "Jackson" in about
        assert "Parameterisation of Speech Lip Movements" in about and "Parameterisation" in CITATION
    finally:
        w.close()


def test_a_session_keeps_the_edited_targets_and_the_synthesised_trajectory(qapp, qtbot, tmp_path, app_manifold):
    from PySide6 import QtCore

    w1 = _window(qapp, _settings(tmp_path / "a.ini"), app_manifold)
    w2 = None
    try:
        ed = w1.editor
        assert ed.set_text("m 0.2 aa 0.3 p 0.2", source="phones")
        tl = ed.timeline
        start = QtCore.QPoint(int(tl.marker_x(1)), int(tl.marker_y()))
        qtbot.mousePress(tl, QtCore.Qt.MouseButton.LeftButton, pos=start)
        qtbot.mouseMove(tl, start + QtCore.QPoint(30, 0))
        qtbot.mouseRelease(tl, QtCore.Qt.MouseButton.LeftButton, pos=start + QtCore.QPoint(30, 0))
        edited = list(ed.targets.frames)
        ed.set_method("linear")
        runner = ed.synthesize()
        qtbot.waitUntil(lambda: runner.state != "running", timeout=60000)
        syn = w1.state.synthetic
        assert syn is not None and list(syn.extra["target_frames"]) == edited
        path = w1.save_session(tmp_path / "work.lipspace.json")

        w2 = _window(qapp, _settings(tmp_path / "b.ini"), app_manifold)
        assert w2.editor.targets is None and w2.state.synthetic is None
        assert w2.open_session(path) is None  # same source: applied at once
        assert list(w2.editor.targets.frames) == edited
        assert [t.label for t in w2.editor.targets.targets] == [t.label for t in ed.targets.targets]
        got = w2.state.synthetic
        np.testing.assert_array_equal(got.Fx, syn.Fx)
        np.testing.assert_array_equal(got.Y, syn.Y)
        assert got.extra["method"] == "linear" and w2.editor.method == "linear"
        assert w2.editor.undo_stack.count() == 0  # a restored session starts a new history
    finally:
        w1.close()
        if w2 is not None:
            w2.close()


def _explore_script(when_shown: str) -> str:
    """A script running ``lipspace explore <argv[1]> --no-restore`` whose window, once its manifold is
    shown, runs the statements ``when_shown`` (with ``self`` the window)."""
    return textwrap.dedent(("""
        import sys
        from PySide6 import QtCore
        from app.main_window import MainWindow

        show = MainWindow.show

        def show_then_act(self):
            show(self)

            def poll():
                if self.state.manifold is not None:
                    {actions}
                else:
                    QtCore.QTimer.singleShot(50, poll)

            QtCore.QTimer.singleShot(50, poll)

        MainWindow.show = show_then_act
        from app.cli import main
        sys.exit(main(["explore", sys.argv[1], "--no-restore"]))
    """).format(actions="\n                    ".join(when_shown.strip().splitlines())))


def test_started_and_closed_window_leaves_the_console_quiet(manifold_file, tmp_path, explore_env):
    r = subprocess.run([sys.executable, "-c", _explore_script("self.close()"), str(manifold_file)],
                       capture_output=True, text=True, env=explore_env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""
    assert (tmp_path / "config" / "lipspace.ini").is_file()  # it did open and close a window


def test_the_window_is_built_before_scikit_learn_is_imported(explore_env):
    """Building and showing the window imports neither scikit-learn nor SciPy's statistics (1.3 s at start-up)
    nor matplotlib's Qt canvas (0.3-0.5 s with the scree plot; the panel, a tab behind the clusters, makes
    its plot when first raised)."""
    code = textwrap.dedent("""
        import sys
        from PySide6 import QtWidgets
        app = QtWidgets.QApplication([])
        from app.main_window import MainWindow
        w = MainWindow()
        w.show()
        app.processEvents()
        print("LOADED", sorted(m for m in ("sklearn", "scipy.stats", "engine.manifold.tangent",
                                           "matplotlib.backends.backend_qtagg") if m in sys.modules))
        w.close()
    """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=explore_env,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip().splitlines()[-1] == "LOADED []", r.stdout


def test_a_manifold_is_loaded_and_prepared_for_the_views_without_scikit_learn(manifold_file, explore_env):
    """What the explorer's worker does to show a manifold file imports neither scikit-learn nor SciPy's
    statistics (the engine's estimators take scikit-learn's API from engine.estimator): a first window
    shows its manifold 1.2-1.5 s sooner."""
    code = textwrap.dedent("""
        import sys
        from app.files.source_loading import load_source
        m, src = load_source(sys.argv[1])
        assert src["kind"] == "manifold" and m.Fy_.shape[0] > 0
        print("LOADED", sorted(m for m in ("sklearn", "scipy.stats", "pandas") if m in sys.modules))
    """)
    r = subprocess.run([sys.executable, "-c", code, str(manifold_file)], capture_output=True, text=True,
                       env=explore_env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip().splitlines()[-1] == "LOADED []", r.stdout


def test_a_window_closed_while_a_task_is_inside_an_engine_step_exits_cleanly(manifold_file, tmp_path, explore_env):
    """Closed while a background task works without a progress call for longer than the close waits (the
    method choice's validation on a large corpus did), ``lipspace explore`` exits 0 with its settings
    written, instead of Qt aborting the process ("QThread: Destroyed while thread is still running")."""
    script = _explore_script("import time\n"
                             "from app.workers import run_task\n"
                             "self._slow = run_task(lambda progress: time.sleep(7), title='slow', dialog=False)\n"
                             "QtCore.QTimer.singleShot(100, self.close)")
    r = subprocess.run([sys.executable, "-c", script, str(manifold_file)], capture_output=True, text=True,
                       env=explore_env, timeout=180)
    assert r.returncode == 0, r.stderr
    assert "QThread" not in r.stderr, r.stderr
    assert (tmp_path / "config" / "lipspace.ini").is_file()


def test_reset_layout_gives_every_dock_its_first_size(qapp, tmp_path):
    """View > Reset layout applies MainWindow.DOCK_SIZES, the sizes the window is built with, whatever was
    moved before (a window on screen: the Lips dock 480 px wide, Lips over the phone clusters 380 : 420,
    so the table shows its rows on a laptop's screen), and the editor's dock as tall as the editor needs."""
    from PySide6 import QtCore

    w = _window(qapp, _settings(tmp_path / "r.ini"))
    shown = ("lips", "clusters", "editor")

    def sizes():
        for _ in range(5):
            qapp.processEvents()
        return {k: w.docks[k].size().toTuple() for k in shown}

    try:
        w.reset_layout()
        first = sizes()
        assert first["lips"][0] == 480 and first["lips"][1] < first["clusters"][1]
        assert abs(w.editor.height() - w.editor.needed_height()) <= 2
        H, V = QtCore.Qt.Orientation.Horizontal, QtCore.Qt.Orientation.Vertical
        w.resizeDocks([w.docks["lips"]], [300], H)
        w.resizeDocks([w.docks["lips"], w.docks["clusters"]], [200, 600], V)
        w.resizeDocks([w.docks["editor"]], [320], V)
        moved = sizes()
        assert all(moved[k] != first[k] for k in shown)
        w.reset_layout()
        assert sizes() == first
    finally:
        w.close()


@pytest.mark.parametrize("signame", ["SIGTERM", "SIGINT"])
def test_a_stop_signal_closes_the_explorer_and_keeps_its_session(manifold_file, tmp_path, signame,
                                                                 signal_when_ready, explore_env):
    """`kill` or Ctrl-C in the terminal stops `lipspace explore`: exit 128 + signal within seconds, one
    line and no traceback, and the session autosaved then is offered back by the next start (before,
    the KeyboardInterrupt was raised inside a Qt slot, printed as a traceback and swallowed)."""
    import signal

    from app.files.autosave import Autosaver

    script = _explore_script("self.state.select_frame(7)\nprint('ready', flush=True)")
    state = tmp_path / "state"
    # 0.5 s after "ready": the event loop is idle, waiting in Qt
    code, _, err, took = signal_when_ready([sys.executable, "-c", script, str(manifold_file)],
                                           explore_env, ready="ready", signum=getattr(signal, signame),
                                           delay=0.5, timeout=30)
    assert code == 128 + getattr(signal, signame), err
    assert took < 10
    assert "Traceback" not in err and "KeyboardInterrupt" not in err
    assert err.strip() == (f"lipspace explore: stopped by {signame}; the window was closed (the session was "
                           "autosaved and is offered back at the next start).")
    recovery = Autosaver(state / "autosave").begin()
    assert recovery is not None  # the next start offers it back
    from app.files.session import load_session

    assert load_session(recovery.session)["selection"]["frame"] == 7


def test_export_dialogs_give_a_name_typed_without_suffix_the_chosen_filters_suffix(qapp, qtbot, tmp_path,
                                                                                   app_manifold, monkeypatch):
    """File > Export trajectory, animation and cluster table write what the chosen filter names when the
    name has no suffix (before: an error dialog, 'cannot export a trajectory as a file without a suffix')."""
    from PySide6 import QtWidgets

    answer = {}
    monkeypatch.setattr(QtWidgets.QFileDialog, "getSaveFileName", staticmethod(lambda *a, **k: answer["save"]))
    w = _window(qapp, _settings(tmp_path / "s.ini"), app_manifold)
    try:
        w.state.set_utterance(app_manifold.corpus_.utterances[0].id)
        assert w.current_trajectory() is not None
        cases = [("traj", "NumPy array (*.npy)", w.export_trajectory_dialog, "traj.npy"),
                 ("table", "CSV table (*.csv)", w.export_trajectory_dialog, "table.csv"),
                 ("anim", "glTF binary (*.glb)", w.export_animation_dialog, "anim.glb"),
                 ("kept.npy", "CSV table (*.csv)", w.export_trajectory_dialog, "kept.npy"),
                 ("clusters", "CSV table (*.csv)", w.export_clusters_dialog, "clusters.csv")]
        for name, chosen, dialog, written in cases:
            answer["save"] = (str(tmp_path / name), chosen)
            dialog()
            qapp.processEvents()
            assert getattr(w, "last_error_message", None) is None, w.last_error_message
            assert (tmp_path / written).is_file(), (name, chosen, sorted(p.name for p in tmp_path.iterdir()))
            assert w.statusBar().currentMessage() == f"wrote {tmp_path / written}"
        n = len(w.current_trajectory())
        assert np.load(tmp_path / "traj.npy").shape[0] == n
        assert not (tmp_path / "traj").exists() and not (tmp_path / "kept.npy.csv").exists()
    finally:
        w.close()

"""What the explorer's start does not do: import matplotlib's figure package before the first frame
(the figures are made on demand), or let D-Bus fork while a load runs (app.qt_app.make_application)."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

pytestmark = pytest.mark.gui


def test_the_explorer_draws_its_manifold_without_matplotlibs_figure_package(manifold_file, explore_env,
                                                                          explore_reporting):
    report = """
        self.manifold_view.plotter.render()
        heavy = ("matplotlib.pyplot", "matplotlib.figure", "matplotlib.backends.backend_agg")
        print("LOADED", [m for m in heavy if m in sys.modules], "pyvista.plotting" in sys.modules, flush=True)
    """
    out = explore_reporting(manifold_file, explore_env, report)
    assert "LOADED [] True" in out, out


def test_the_figure_menu_lists_every_figure_by_its_description(qapp, app_manifold):
    from app.figures import DESCRIPTIONS, FIGURES
    from app.main_window import MainWindow

    win = MainWindow(app_manifold, source={"path": None, "preset": "small"})
    try:
        texts = [a.text() for a in win.findChildren(type(win.menuBar().actions()[0]))]
        for name, description in DESCRIPTIONS.items():
            assert f"{name}: {description[:60]}…" in texts
        assert list(FIGURES) == list(DESCRIPTIONS)
    finally:
        win.close()


_FORKS = textwrap.dedent("""
    import resource, sys, threading
    from PySide6 import QtWidgets

    def children():  # page faults of reaped child processes: grows when a child was forked and reaped
        return resource.getrusage(resource.RUSAGE_CHILDREN).ru_minflt

    if sys.argv[1] == "lipspace":
        from app.qt_app import make_application
        app = make_application([])
    else:
        app = QtWidgets.QApplication([])
    before = children()
    w = QtWidgets.QWidget()
    w.show()
    app.processEvents()
    print("FORKED", children() > before)
""")


def test_no_child_is_forked_when_the_first_widget_is_made_after_the_application(explore_env):
    """Without a session bus the accessibility bridge's D-Bus connection forks; a fork while a worker's
    BLAS threads ran deadlocked the start. make_application connects it before any worker starts."""
    env = {k: v for k, v in explore_env.items() if k != "DBUS_SESSION_BUS_ADDRESS"}

    def forked(kind: str) -> bool:
        r = subprocess.run([sys.executable, "-c", _FORKS, kind], capture_output=True, text=True, env=env, timeout=60)
        assert r.returncode == 0, r.stderr
        return "FORKED True" in r.stdout

    if not forked("plain"):
        pytest.skip("Qt forks nothing for its first widget here (a session bus, or no D-Bus launch)")
    assert not forked("lipspace")

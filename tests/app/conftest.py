"""GUI test support: the shared explorer window, its settings, and a skip where there is no display.

The display is the virtual X server pytest-xvfb starts for the run (the ``xvfb_*`` settings in
pyproject.toml: 1600x1200x24); Qt's QtInteractor needs a real X display
(QT_QPA_PLATFORM=offscreen does not work with VTK's OpenGL widget). Where neither Xvfb nor a
DISPLAY is there, tests marked ``gui`` are skipped with the reason.
"""
from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest


def pytest_runtest_setup(item):
    if item.get_closest_marker("gui") is not None and not os.environ.get("DISPLAY"):
        pytest.skip("GUI test needs a display: install Xvfb (the xvfb package; pytest-xvfb starts it) or run "
                    "under an X server")


@pytest.fixture(scope="session")
def app_manifold(small_manifold):
    """The small synthetic manifold shared by the app tests (built once per session), its
    synthesis methods measured on validation here, once (the editor's default and the
    manifold method read that measurement; on a fresh cache it takes tens of seconds, which
    no GUI test's wait should include)."""
    from engine.synthesis.method_choice import choose_methods

    choose_methods(small_manifold)
    return small_manifold


@pytest.fixture(scope="session")
def manifold_file(app_manifold, tmp_path_factory):
    """:func:`app_manifold` saved as a manifold file, for the explorer opened on a file."""
    path = tmp_path_factory.mktemp("manifold-file") / "small.npz"
    app_manifold.save(path)
    return path


@contextlib.contextmanager
def shown_main_window(qapp, manifold, size=(1300, 850)):
    """The explorer window on ``manifold`` (the small preset), shown at ``size``; closed on exit."""
    from app.main_window import MainWindow

    w = MainWindow(manifold, source={"path": None, "preset": "small"})
    try:
        w.resize(*size)
        w.show()
        for _ in range(5):
            qapp.processEvents()
        yield w
    finally:
        w.close()


@pytest.fixture(scope="session")
def main_window_factory():
    """:func:`shown_main_window`: ``with main_window_factory(qapp, manifold) as w: ...``."""
    return shown_main_window


def reset_window(window, qapp) -> None:
    """A shared explorer window back to how a fresh one starts: playback stopped, no utterance, every
    view field and setting at its default (no selection, path, component or phone filter; density
    colouring, future hemisphere), both undo histories empty, the events processed."""
    s = window.state
    s.set_playing(False)
    s.set_utterance(None)
    s.reset_view()
    s.reset_settings()
    window.view_undo_stack.clear()
    window.editor.undo_stack.clear()
    qapp.processEvents()


@pytest.fixture
def fresh_window(shared_window, qapp):
    """The test module's ``shared_window`` (a module-scoped fixture the module declares: the window is
    built once per module, its full rebuild tested there once), reset by :func:`reset_window` for
    this test."""
    reset_window(shared_window, qapp)
    return shared_window


@pytest.fixture(scope="session", autouse=True)
def _window_settings_in_tmp(tmp_path_factory):
    """Windows of the tests keep geometry, layout and recent files in a temporary folder, not the user's."""
    old = os.environ.get("LIPSPACE_CONFIG_DIR")
    os.environ["LIPSPACE_CONFIG_DIR"] = str(tmp_path_factory.mktemp("config"))
    yield
    if old is None:
        os.environ.pop("LIPSPACE_CONFIG_DIR", None)
    else:
        os.environ["LIPSPACE_CONFIG_DIR"] = old


def _forget_window_settings():
    (Path(os.environ["LIPSPACE_CONFIG_DIR"]) / "lipspace.ini").unlink(missing_ok=True)


@pytest.fixture(scope="module", autouse=True)
def _fresh_window_settings_per_module(_window_settings_in_tmp):
    """A module's shared window starts from default settings, whatever an earlier module's window left."""
    _forget_window_settings()


@pytest.fixture(autouse=True)
def _fresh_window_settings_per_test(_window_settings_in_tmp):
    """So does every window a test opens (a dock hidden by one test never hides it in the next)."""
    _forget_window_settings()


@pytest.fixture
def dead_pid():
    """A function giving the id of a process that has just exited (a crashed explorer's, for autosave records)."""
    import sys

    def new() -> int:
        p = subprocess.Popen([sys.executable, "-c", "pass"])
        p.wait()
        return p.pid

    return new


@pytest.fixture
def run_cli_window(qapp):
    """Run ``lipspace <argv>`` with its event loop until a shown main window is ``ready``.

    ``run(argv, ready, look, *, each=None, timeout_s=60)`` calls ``each()`` at every poll
    (every 100 ms; e.g. to answer a dialog), and once a visible ``MainWindow`` makes
    ``ready(window)`` true, ``look(window)``, then closes it and ends the loop. Returns
    ``(exit code, look's result)``; the result is None when no window was ready in time.
    """
    from PySide6 import QtCore, QtWidgets

    from app.cli import main
    from app.main_window import MainWindow

    def run(argv, ready, look, *, each=None, timeout_s=60.0):
        seen = []
        timer = QtCore.QElapsedTimer()

        def poll():
            if each is not None:
                each()
            wins = [w for w in QtWidgets.QApplication.topLevelWidgets() if isinstance(w, MainWindow) and w.isVisible()]
            done = [w for w in wins if ready(w)]
            if done or timer.elapsed() > 1000 * timeout_s:
                if done:
                    seen.append(look(done[0]))
                for w in wins:
                    w.close()
                qapp.quit()
                return
            QtCore.QTimer.singleShot(100, poll)

        timer.start()
        # the test ends the event loop itself, once: a second quit (closing the last window)
        # would be left pending and end the next test's dialog loop at once
        qapp.setQuitOnLastWindowClosed(False)
        QtCore.QTimer.singleShot(100, poll)
        try:
            code = main(list(argv))
        finally:
            qapp.setQuitOnLastWindowClosed(True)
        return code, (seen[0] if seen else None)

    return run


def articulograph_manifold(*, n_speakers=2, n_utterances=2, duration_s=(2.0, 2.0), seed=11, n_states=16,
                           axes=None, name="ema"):
    """A manifold of generated 4-sensor articulograph recordings as import makes them
    (:func:`engine.talker.example_corpora.articulograph_corpus`: UL, LL, LC, RC kept, no phone labels,
    utterance centring, 60 Hz), each utterance naming its speaker."""
    import warnings

    from engine.manifold.model import Manifold
    from engine.recordings.corpus import CorpusWarning
    from engine.talker.example_corpora import articulograph_corpus

    corpus = articulograph_corpus(n_speakers=n_speakers, n_utterances=n_utterances, duration_s=duration_s,
                                  seed=seed, axes=axes, name=name)
    with warnings.catch_warnings():  # a state or two cut off by a few seconds of speech is not what tests are about
        warnings.simplefilter("ignore", CorpusWarning)
        return Manifold(n_states=n_states).fit(corpus)


@pytest.fixture(scope="session")
def make_articulograph_manifold():
    """:func:`articulograph_manifold`: ``make_articulograph_manifold(n_speakers=3, ...)``."""
    return articulograph_manifold


@pytest.fixture(scope="session")
def field_manifold(conditions):
    """The conditions' manifold (three levels ``a``, ``b``, ``c`` of field ``condition``, ten texts said twice in
    each) with its utterances carrying the fields a lab's metadata gives (condition, text, speaker, repetition)."""
    import copy

    from engine.comparison.fields import attach_fields

    cc, m = conditions
    out = copy.copy(m)
    out.corpus_ = attach_fields(m.corpus_, cc.fields)
    return out


@pytest.fixture(scope="session")
def condition_comparison(field_manifold):
    """``condition`` b and c against a on :func:`field_manifold`, paired by text (few permutations: a GUI's run)."""
    from app.models.compare_run import ComparisonRequest, run_comparison

    return run_comparison(field_manifold, ComparisonRequest(field="condition", levels=("a", "b", "c"),
                                                            paired_by="text", n_permutations=199, n_bootstrap=99))


def _tab_bars_name_shown_docks(w) -> None:
    """Every tab bar drawn in ``w`` names shown docks only: a bar Qt left over a hidden dock's tab drew
    "ltiples" beside the lips."""
    from PySide6 import QtWidgets

    shown = {d.windowTitle() for d in w.docks.values() if not d.isHidden()}
    for t in w.findChildren(QtWidgets.QTabBar):
        if not t.isVisible() or t.parentWidget() is not w or t.count() < 2 or not t.geometry().intersects(w.rect()):
            continue
        names = {t.tabText(i) for i in range(t.count())}
        assert names <= shown, (names - shown, t.geometry().getRect())


@pytest.fixture
def tab_bar_probe():
    """:func:`_tab_bars_name_shown_docks`: the window's dock tab bars name only shown docks."""
    return _tab_bars_name_shown_docks


def _signal_when_ready(cmd, env, *, ready: str, signum, delay: float, timeout: float):
    """Start ``cmd``, wait for its stdout line ``ready``, wait ``delay`` s more, send ``signum``.

    Returns ``(returncode, stdout, stderr, seconds from the signal to the exit)``; the process is killed if
    it outlives the test."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        assert proc.stdout.readline().strip() == ready
        time.sleep(delay)
        proc.send_signal(signum)
        sent = time.monotonic()
        out, err = proc.communicate(timeout=timeout)
        return proc.returncode, out, err, time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


@pytest.fixture
def signal_when_ready():
    """:func:`_signal_when_ready`: a stop signal sent to a started explorer once it says it is ready."""
    return _signal_when_ready


@pytest.fixture
def explore_env(tmp_path) -> dict:
    """The environment of an explorer started in a subprocess: its state, settings and cache under the
    test's ``tmp_path``, Qt's logging as set (no QT_LOGGING_RULES inherited)."""
    env = {k: v for k, v in os.environ.items() if k != "QT_LOGGING_RULES"}
    env.update(LIPSPACE_STATE_DIR=str(tmp_path / "state"), LIPSPACE_CONFIG_DIR=str(tmp_path / "config"),
               LIPSPACE_CACHE_DIR=str(tmp_path / "cache"))
    return env


#: an explorer on the file in argv[1] that runs the report (with ``self``, the window) once its manifold is
#: on screen, then closes; the setup runs first (it may wrap the window's methods)
_EXPLORE_REPORTING = """
import sys
from PySide6 import QtCore
import app.main_window as mw
{setup}
_show = mw.MainWindow.show


def _show_then_report(self):
    _show(self)

    def poll():
        if self.state.manifold is None:
            QtCore.QTimer.singleShot(50, poll)
            return
{report}
        self.close()

    QtCore.QTimer.singleShot(50, poll)


mw.MainWindow.show = _show_then_report
from app.cli import main
sys.exit(main(["explore", sys.argv[1], "--no-restore"]))
"""


def _explore_reporting(path, env: dict, report: str, setup: str = "") -> str:
    script = _EXPLORE_REPORTING.format(setup=textwrap.dedent(setup),
                                       report=textwrap.indent(textwrap.dedent(report).strip(), " " * 8))
    r = subprocess.run([sys.executable, "-c", script, str(path)], capture_output=True, text=True, env=env,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    return r.stdout


@pytest.fixture
def explore_reporting():
    """``explore_reporting(path, env, report, setup="")``: ``lipspace explore path`` in a subprocess that runs
    the code ``report`` (``self`` is the window) once the manifold is shown, then closes; its stdout."""
    return _explore_reporting

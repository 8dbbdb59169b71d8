"""A load started before its window exists is taken over by the window (app.workers.start_task,
connect_outcome; app.launching.launch): its outcome and progress reach the window whether the
task ended before the window took it or after."""
from __future__ import annotations

import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

pytestmark = pytest.mark.gui


def _ended(task):
    """``task`` that sets ``ended`` as it returns or raises, and ``ended``: a test waits for it without running
    the GUI thread's event loop (as while a window is being built), so the task's outcome stays queued."""
    import threading

    ended = threading.Event()

    def wrapped(progress):
        try:
            return task(progress)
        finally:
            ended.set()

    return wrapped, ended


def _wait(ended, timeout_s: float = 20.0) -> None:
    assert ended.wait(timeout_s), "the task did not end"
    time.sleep(0.2)  # the worker's outcome signal follows its task's return


@pytest.mark.parametrize("outcome", ["done", "failed", "cancelled"])
def test_a_task_that_ended_before_its_window_gives_its_outcome_and_progress_once(qapp, outcome):
    from PySide6 import QtWidgets

    from app.user_messages import UserError
    from app.views.task_progress import attach_status_progress
    from app.workers import connect_outcome, start_task

    def task(progress):
        progress("reading", 0, 2)
        progress("reading", 1, 2)
        progress("preparing", 0, 1)
        if outcome == "failed":
            raise UserError("the file is cut short")
        if outcome == "cancelled":
            runner.cancel()
            progress("preparing", 1, 1)  # raises Cancelled
        return 42

    wrapped, ended = _ended(task)
    runner = start_task(wrapped, title="Loading")
    _wait(ended)
    assert runner.state == "running"  # its outcome waits in the GUI thread's queue
    win = QtWidgets.QMainWindow()
    got = []
    try:
        connect_outcome(runner, parent=win, on_done=lambda r: got.append(("done", r)),
                        on_error=lambda msg, _tb: got.append(("failed", msg)),
                        on_cancel=lambda: got.append(("cancelled",)))
        bar = attach_status_progress(win, runner, "loading m.npz")
        assert bar.isVisibleTo(win)
        for _ in range(20):
            qapp.processEvents()
        assert runner.state == outcome
        assert got == [{"done": ("done", 42), "failed": ("failed", "the file is cut short"),
                        "cancelled": ("cancelled",)}[outcome]]
        stages = [name for name, _t in bar.stages]
        # reported before the window took the task (a task being cancelled shows no more progress)
        assert stages == (["loading m.npz"] if outcome == "cancelled" else ["loading m.npz", "reading", "preparing"])
        assert not bar.isVisibleTo(win) and bar.runner is None  # the status bar's progress ended with the task
        assert runner.parent() is win
    finally:
        win.close()


@pytest.mark.parametrize("outcome", ["done", "failed"])
def test_a_window_that_takes_over_an_ended_task_still_gets_its_outcome(qapp, outcome):
    """connect_outcome after the task's outcome reached the GUI thread (nobody listened): it is sent again
    at the event loop's next turn, once."""
    from PySide6 import QtWidgets

    from app.workers import connect_outcome, start_task

    def task(progress):
        if outcome == "failed":
            raise ValueError("broken")
        return "m"

    wrapped, ended = _ended(task)
    runner = start_task(wrapped, title="Loading")
    _wait(ended)
    for _ in range(20):
        qapp.processEvents()
    assert runner.state == outcome
    win = QtWidgets.QMainWindow()
    got = []
    try:
        connect_outcome(runner, parent=win, on_done=got.append, on_error=lambda msg, _tb: got.append(msg))
        assert got == []  # not from inside the call: at the next turn
        for _ in range(5):
            qapp.processEvents()
        assert got == (["m"] if outcome == "done" else ["ValueError: broken"])
    finally:
        win.close()


def test_the_explorer_starts_loading_its_file_before_it_builds_its_window(manifold_file, explore_env,
                                                                           explore_reporting):
    """``lipspace explore m.npz``: the load runs while the window is being built (the window's imports and
    construction take about as long as loading the talker), the window takes it over and shows it; the
    status bar saw the load's stages from its start."""
    setup = """
        import app.workers as workers

        init = mw.MainWindow.__init__
        seen = {}

        def recording_init(self, *a, **k):
            seen["loading while built"] = workers.running()
            init(self, *a, **k)

        mw.MainWindow.__init__ = recording_init
    """
    report = """
        from app.views.task_progress import TaskProgress

        bar = self.findChild(TaskProgress, "task_progress")
        print("SEEN", seen["loading while built"], self.state.source["kind"],
              "|".join(name for name, _t in bar.stages), flush=True)
    """
    out = explore_reporting(manifold_file, explore_env, report, setup)
    line = [ln for ln in out.splitlines() if ln.startswith("SEEN ")]
    assert line, out
    _, running, kind, stages = line[0].split(" ", 3)
    assert running == "True" and kind == "manifold"
    assert stages.split("|")[:3] == [f"loading {manifold_file.name}", "loading manifold", "preparing the views"]


def test_the_gestures_of_a_new_manifold_are_found_after_the_event_loop_turns(qapp, app_manifold):
    """The editor's gesture finder starts once the events waiting when a manifold is shown (its first frame)
    are handled, not inside the showing, and still finds the gestures."""
    from app.main_window import MainWindow

    win = MainWindow()
    try:
        win.set_manifold(app_manifold)
        finder = win.editor._finder
        assert finder is not None and finder.state == "running" and not finder.thread.isRunning()
        assert win.state.gestures is None
        assert finder.wait(60_000) and finder.state == "done"
        assert win.state.gestures is not None and win.state.gestures.times.shape[0] > 0
    finally:
        win.close()


def test_the_state_graph_of_a_loaded_manifold_is_prepared_for_queries_after_its_first_frame(qapp, manifold_file):
    """A manifold read from a file keeps its graph's csr matrices as arrays (no SciPy in the load); once shown,
    a worker started after the event loop turns builds what the first click's hemisphere needs."""
    from app.main_window import MainWindow
    from engine.manifold.model import Manifold

    m = Manifold.load(manifold_file)
    graph = m.states_
    assert "adjacency_" in graph.__dict__["_csr_parts"]
    win = MainWindow()
    try:
        win.set_manifold(m, source={"path": str(manifold_file), "preset": "small", "kind": "manifold"})
        prep = win.manifold_view.query_prep
        assert prep is not None and prep.state == "running" and not prep.thread.isRunning()
        assert "A" not in graph.__dict__.get("_cache", {})  # not built while the manifold was being shown
        assert prep.wait(60_000) and prep.state == "done"
        assert {"A", "AT"} <= set(graph.__dict__["_cache"]) and "adjacency_" not in graph.__dict__["_csr_parts"]
        fut, past = graph.hemispheres(0)
        assert fut[0] == 0 and past[0] == 0 and np.isfinite(fut).sum() > 1
    finally:
        win.close()


def test_a_load_that_ended_while_the_window_was_built_is_shown_at_once(manifold_file, explore_env):
    """A load done before the window takes it over reaches the window inside open_source, before the event loop
    (and the window's first paint) runs."""
    script = textwrap.dedent("""
        import sys, time
        from PySide6 import QtCore
        import app.main_window as mw

        init, open_source = mw.MainWindow.__init__, mw.MainWindow.open_source

        def slow_init(self, *a, **k):
            init(self, *a, **k)
            time.sleep(3)  # the small file's load ends meanwhile

        def open_and_report(self, *a, **k):
            runner = open_source(self, *a, **k)
            print("SHOWN", self.state.manifold is not None, runner.state, flush=True)
            QtCore.QTimer.singleShot(100, self.close)
            return runner

        mw.MainWindow.__init__, mw.MainWindow.open_source = slow_init, open_and_report
        from app.cli import main
        sys.exit(main(["explore", sys.argv[1], "--no-restore"]))
    """)
    r = subprocess.run([sys.executable, "-c", script, str(manifold_file)], capture_output=True, text=True,
                       env=explore_env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "SHOWN True done" in r.stdout, r.stdout

"""Warnings from worker threads reach their own task and window, never another thread's.

``warnings.catch_warnings`` swaps process-global state (before Python 3.14), so the
workers route data warnings through one ``showwarning`` that dispatches by thread id
(:data:`app.workers.WARNINGS`). These tests make two threads warn at the same time
and check each warning arrives where it belongs.
"""
from __future__ import annotations

import threading
import time
import warnings

import pytest

from engine.recordings.corpus import CorpusWarning

N_WARNINGS = 150


def _recorder(into: list):
    def show(message, category, filename, lineno, file=None, line=None):
        into.append((str(message), category))
    return show


def _warn_loop(tag: str, order: list, n: int = N_WARNINGS, category=CorpusWarning):
    for k in range(n):
        order.append((tag, k))
        warnings.warn(f"{tag} {k}", category, stacklevel=1)
        time.sleep(0.0005)  # let the other thread run in between


def test_router_dispatches_by_thread_without_qt(monkeypatch):
    from app.workers import WarningRouter

    main_seen: list = []
    monkeypatch.setattr(warnings, "showwarning", _recorder(main_seen))
    router = WarningRouter()
    router.install()
    assert router.installed and warnings.filters[0][:3:2] == ("always", CorpusWarning)
    router.install()  # idempotent: does not wrap itself
    assert router._previous is not router.showwarning
    routed: list = []
    order: list = []
    start = threading.Barrier(2)

    def worker():
        with router.route(routed.append):
            start.wait(10)
            _warn_loop("worker", order)
        warnings.warn("worker after its task", CorpusWarning, stacklevel=1)  # no longer routed

    t = threading.Thread(target=worker)
    t.start()
    start.wait(10)
    _warn_loop("main", order)
    t.join(10)
    assert routed == [f"worker {k}" for k in range(N_WARNINGS)]
    unrouted = [m for m, _c in main_seen]
    assert [m for m in unrouted if m.startswith("main")] == [f"main {k}" for k in range(N_WARNINGS)]
    assert [m for m in unrouted if not m.startswith("main")] == ["worker after its task"]
    tags = [tag for tag, _k in order]
    first_main, last_worker = tags.index("main"), len(tags) - 1 - tags[::-1].index("worker")
    assert first_main < last_worker  # the two threads really warned at the same time
    with pytest.raises(RuntimeError, match="already routes"):
        with router.route(routed.append), router.route(routed.append):
            pass


def test_router_reinstalled_over_a_handler_that_wraps_it_does_not_loop(monkeypatch):
    """The CLI wraps the handler it finds (the router) and a task re-installs the router over it."""
    from app.workers import WarningRouter

    seen: list = []
    monkeypatch.setattr(warnings, "showwarning", _recorder(seen))
    monkeypatch.setattr(warnings, "_showwarning_orig", _recorder(seen))  # Python's own, at the end
    router = WarningRouter()
    router.install()
    inner = warnings.showwarning

    def cli_show(message, category, filename, lineno, file=None, line=None):
        inner(message, category, filename, lineno, file, line)

    warnings.showwarning = cli_show
    router.install()
    warnings.warn("once", CorpusWarning, stacklevel=1)  # GUI thread: router -> CLI handler -> router -> Python's own
    assert seen == [("once", CorpusWarning)]


@pytest.mark.gui
def test_worker_warning_reaches_the_status_bar_while_the_gui_thread_warns(qapp, qtbot, monkeypatch):
    from app.main_window import MainWindow
    from app.workers import run_task

    main_seen: list = []
    monkeypatch.setattr(warnings, "showwarning", _recorder(main_seen))  # the process's handler at app start
    win = MainWindow()
    qtbot.addWidget(win)
    order: list = []
    start = threading.Barrier(2)

    def task(progress):
        progress("working", 0, 1)
        start.wait(10)
        _warn_loop("worker", order)
        return "done"

    runner = run_task(task, parent=win, dialog=False)
    start.wait(10)
    _warn_loop("main", order)  # the GUI thread warns while the worker does
    qtbot.waitUntil(lambda: runner.state != "running", timeout=20000)
    qtbot.waitUntil(lambda: len(runner.warnings) == N_WARNINGS, timeout=5000)
    assert runner.state == "done" and runner.result == "done"  # a data warning never fails the task
    assert runner.warnings == [f"worker {k}" for k in range(N_WARNINGS)]  # all, in order, none of main's
    assert win.statusBar().currentMessage() == f"warning: worker {N_WARNINGS - 1}"
    assert main_seen == [(f"main {k}", CorpusWarning) for k in range(N_WARNINGS)]  # not swallowed, not misrouted
    tags = [tag for tag, _k in order]
    assert tags.index("main") < len(tags) - 1 - tags[::-1].index("worker")  # they overlapped


@pytest.mark.gui
def test_other_warnings_in_a_worker_keep_the_process_filters(qapp, qtbot):
    from app.workers import TaskRunner

    def task(progress):
        warnings.warn("not about the data", RuntimeWarning, stacklevel=1)
        return 1

    # pytest runs with filterwarnings=error: a non-data warning still raises in the worker
    r = TaskRunner(task, dialog=False).start()
    assert r.wait(10000) and r.state == "failed" and "RuntimeWarning: not about the data" in r.error[0]
    assert r.warnings == []


@pytest.mark.gui
@pytest.mark.parametrize("wrapped", [False, True], ids=["bare", "under-plain-errors"])
def test_memory_error_in_a_task_is_one_plain_message_with_the_size_and_a_hint(qapp, qtbot, wrapped):
    """numpy's 'Unable to allocate ... for an array with shape ...' never reaches the window."""
    import numpy as np

    from app.out_of_memory import installed_bytes
    from app.workers import TaskRunner

    def task(progress):
        progress("embedding", 0, 1)
        return np.empty((10**7, 10**6))  # 80 TB: refused by the allocator at once

    if wrapped:  # the window's tasks go through a plain-language wrapper whose cause is the MemoryError
        inner = task

        def task(progress):
            try:
                return inner(progress)
            except MemoryError as exc:
                raise RuntimeError("There is not enough memory.") from exc

    r = TaskRunner(task, dialog=False, title="Building the manifold…").start()
    assert r.wait(10000) and r.state == "failed"
    msg = r.error[0]
    assert msg.startswith("Lipspace ran out of memory while trying to finish this task (Building the manifold)")
    assert "it needed 80000.0 GB more at once" in msg and "--landmarks 2000" in msg and "--resample 30" in msg
    if installed_bytes():
        assert "this computer has" in msg
    assert "MemoryError" not in msg and "allocate" not in msg and "dtype" not in msg and "\n" not in msg
    assert "MemoryError" in r.error[1]  # the traceback is kept for the details



@pytest.mark.gui
def test_a_quick_task_never_touches_its_progress_dialog(qapp, qtbot, monkeypatch):
    """A modal QProgressDialog's setValue processes events (a whole-window repaint, ~20 ms in
    software GL): a task done before the dialog would open must not call it."""
    from PySide6 import QtWidgets

    from app.workers import TaskRunner

    calls: list = []
    real = QtWidgets.QProgressDialog.setValue
    monkeypatch.setattr(QtWidgets.QProgressDialog, "setValue", lambda self, v: (calls.append(v), real(self, v)))

    def task(progress):
        progress("quick", 0, 1)
        progress("quick", 1, 1)
        return 2

    r = TaskRunner(task).start()
    assert r.wait(10000) and r.state == "done" and r.result == 2
    qtbot.wait(50)
    assert calls == [] and not r.dialog.isVisible()


@pytest.mark.gui
def test_a_slow_task_opens_its_dialog_at_the_latest_progress(qapp, qtbot):
    from app.workers import DIALOG_DELAY_MS, TaskRunner

    release = threading.Event()

    def task(progress):
        progress("reading", 3, 10)
        release.wait(20)
        return 1

    t0 = time.perf_counter()
    r = TaskRunner(task, title="Reading").start()
    try:
        qtbot.waitUntil(lambda: r._progress == ("reading", 3, 10), timeout=5000)
        if time.perf_counter() - t0 < 0.8 * DIALOG_DELAY_MS / 1000:
            assert not r.dialog.isVisible()  # not before the delay
        qtbot.waitUntil(r.dialog.isVisible, timeout=DIALOG_DELAY_MS + 5000)
        assert r.dialog.value() == 3 and r.dialog.maximum() == 10 and r.dialog.labelText().startswith("reading 3/10 · ")
    finally:
        release.set()
    assert r.wait(10000) and r.state == "done" and not r.dialog.isVisible()


def test_a_progress_dialog_moves_between_reports_and_says_the_time_left(qapp, qtbot):
    """A long stage reported seldom (the first "Best on validation" sat at 0 % for 52 s): the dialog's label
    counts the seconds between reports and, once a count is made, says the time left."""
    import threading

    from PySide6 import QtWidgets

    from app.workers import run_task

    go = threading.Event()

    def task(progress):
        progress("validation", 0, 4)
        go.wait(10)
        progress("validation", 1, 4)
        go.clear()
        go.wait(10)
        return 1

    parent = QtWidgets.QWidget()
    runner = run_task(task, parent=parent, title="Synthesising")
    try:
        qtbot.waitUntil(lambda: runner.dialog.isVisible(), timeout=5000)
        first = runner.dialog.labelText()
        qtbot.waitUntil(lambda: runner.dialog.labelText() != first, timeout=3000)  # it lives between reports
        assert runner.dialog.labelText().startswith("validation") and runner.dialog.maximum() == 4
        go.set()
        qtbot.waitUntil(lambda: "left" in runner.dialog.labelText() and "estimating" not in runner.dialog.labelText(),
                        timeout=5000)
    finally:
        go.set()
        runner.wait(10000)
        parent.deleteLater()

"""Long work off the GUI thread: a QThread worker with progress and cancel.

``task(progress)`` runs in a worker thread; ``progress(stage, done, total)`` is the
engine's progress callback: it forwards to the GUI through a queued signal and
raises :class:`engine.progress.Cancelled` once the user has pressed Cancel, which
unwinds the engine cleanly. Results and errors come back on the GUI thread.

Engine warnings about the user's data (:class:`engine.recordings.corpus.CorpusWarning`) raised in
a worker thread go to that worker's ``warned`` signal through :data:`WARNINGS`, one
process-wide ``warnings.showwarning`` that dispatches by thread id. Nothing enters or
leaves ``warnings.catch_warnings`` in a worker thread: that context manager swaps
process-global state (before Python 3.14), so one thread's block would capture, or
restore over, another thread's warnings.
"""
from __future__ import annotations

import threading
import traceback
import warnings

from PySide6 import QtCore, QtWidgets

from app.user_messages import UserError
from engine.progress import Cancelled
from engine.recordings.corpus import CorpusWarning

__all__ = ["Worker", "TaskRunner", "run_task", "start_task", "connect_outcome", "run_blocking", "cancel_all", "running",
           "WarningRouter", "WARNINGS"]


class WarningRouter:
    """Routes data warnings raised in registered threads to a per-thread callback.

    :meth:`install` (on the GUI thread) makes :meth:`showwarning` the process's
    ``warnings.showwarning``, wrapping whatever was there, and puts an ``"always"``
    filter for :class:`CorpusWarning` first, so a data warning is never turned into an
    error or deduplicated away before it reaches the window. A worker thread
    registers itself with :meth:`route` for the duration of its task: a
    ``CorpusWarning`` raised in that thread calls its callback (which emits a queued Qt
    signal); every other warning, and every warning of any other thread (the GUI
    thread included), goes to the wrapped ``showwarning`` unchanged. Warnings raised in
    threads the engine itself starts are not routed (they go to the wrapped handler).
    """

    def __init__(self):
        self._routes: dict[int, object] = {}
        self._lock = threading.Lock()
        self._previous = None
        self._local = threading.local()

    def install(self) -> None:
        """Install (or re-install) the dispatcher; idempotent. Call on the GUI thread.

        Called whenever a task starts, because a ``catch_warnings`` block that was
        entered before the install (a test harness, the CLI wrapper) restores the old
        handler and filters when it exits.
        """
        if warnings.showwarning != self.showwarning:
            self._previous = warnings.showwarning
            warnings.showwarning = self.showwarning
        first = warnings.filters[0] if warnings.filters else None
        if first is None or first[0] != "always" or first[2] is not CorpusWarning or first[1] or first[3]:
            warnings.filterwarnings("always", category=CorpusWarning)

    @property
    def installed(self) -> bool:
        return warnings.showwarning == self.showwarning

    def route(self, callback):
        """Context manager: data warnings of the calling thread go to ``callback(message)``."""
        return _Route(self, threading.get_ident(), callback)

    def showwarning(self, message, category, filename, lineno, file=None, line=None):
        callback = self._routes.get(threading.get_ident())
        if callback is not None and issubclass(category, CorpusWarning):
            callback(str(message))
            return
        if getattr(self._local, "busy", False):
            # the wrapped handler wraps this router in turn (it was installed over the
            # router, then the router re-installed over it): end the loop with Python's own
            warnings._showwarning_orig(message, category, filename, lineno, file, line)
            return
        self._local.busy = True
        try:
            (self._previous or warnings._showwarning_orig)(message, category, filename, lineno, file, line)
        finally:
            self._local.busy = False


class _Route:
    def __init__(self, router, ident, callback):
        self.router, self.ident, self.callback = router, ident, callback

    def __enter__(self):
        with self.router._lock:
            if self.ident in self.router._routes:
                raise RuntimeError(f"thread {self.ident} already routes its warnings to a task")
            self.router._routes[self.ident] = self.callback
        return self

    def __exit__(self, *_exc):
        with self.router._lock:
            self.router._routes.pop(self.ident, None)
        return False


#: the process's one router (see :class:`WarningRouter`)
WARNINGS = WarningRouter()

#: a task's progress dialog opens once the task has run this long (ms); quicker tasks show none
DIALOG_DELAY_MS = 300


class Worker(QtCore.QObject):
    """Runs ``task(progress)`` once in its thread; emits progress / done / failed / cancelled."""

    progress = QtCore.Signal(str, int, int)
    done = QtCore.Signal(object)
    failed = QtCore.Signal(str, str)  # message, traceback
    cancelled = QtCore.Signal()
    warned = QtCore.Signal(str)  # an engine warning about the user's data

    def __init__(self, task, *, doing: str = "finish this task"):
        super().__init__()
        self.task = task
        self.doing = doing  # completes "ran out of memory while trying to ..."
        self._cancel = threading.Event()

    def cancel(self) -> None:
        """Ask the task to stop at its next progress report."""
        self._cancel.set()

    @property
    def cancel_requested(self) -> bool:
        return self._cancel.is_set()

    def report(self, stage, done, total) -> None:
        """The progress callback handed to the engine (runs in the worker thread)."""
        if self._cancel.is_set():
            raise Cancelled("cancelled by the user")
        self.progress.emit(str(stage), int(done), int(total))

    @QtCore.Slot()
    def run(self) -> None:
        try:
            # data warnings of this thread go to the window (WARNINGS, installed by the
            # runner on the GUI thread); every other warning keeps the process's handling
            with WARNINGS.route(self.warned.emit):
                result = self.task(self.report)
        except Cancelled:
            self.cancelled.emit()
        except Exception as exc:  # noqa: BLE001 - shown to the user, with the traceback
            oom = exc if isinstance(exc, MemoryError) else exc.__cause__
            if isinstance(oom, MemoryError):  # also under a plain-language wrapper: the size and what lowers it
                from app.out_of_memory import memory_message

                self.failed.emit(memory_message(oom, doing=self.doing), traceback.format_exc())
                return
            # a UserError (app.user_messages) is already written for the user: shown as it is
            msg = str(exc) if isinstance(exc, UserError) else f"{type(exc).__name__}: {exc}"
            self.failed.emit(msg, traceback.format_exc())
        else:
            if self._cancel.is_set():
                self.cancelled.emit()
            else:
                self.done.emit(result)


class TaskRunner(QtCore.QObject):
    """Owns one worker thread and (optionally) a progress dialog for it.

    Signals ``finished(result)``, ``failed(message, traceback)``, ``cancelled()`` and
    ``progressed(stage, done, total)`` are emitted on the GUI thread. Keep a reference until one
    of the first three fires. Progress reported before a view connects to ``progressed`` (a task
    started before its window, :func:`start_task`) reaches it still: the worker's reports are
    queued to the runner from the start and relayed when the GUI thread's event loop runs.
    """

    finished = QtCore.Signal(object)
    failed = QtCore.Signal(str, str)
    cancelled = QtCore.Signal()
    warned = QtCore.Signal(str)
    progressed = QtCore.Signal(str, int, int)

    def __init__(self, task, *, parent=None, title: str = "Working", dialog: bool = True):
        super().__init__(parent)
        self.result = None
        self.error = None
        self.state = "running"
        self.worker = Worker(task, doing=f"finish this task ({title.rstrip('.…')})")
        self.thread = QtCore.QThread()
        self.worker.moveToThread(self.thread)
        self.thread.started.connect(self.worker.run)
        self.worker.done.connect(self._on_done)
        self.worker.failed.connect(self._on_failed)
        self.worker.cancelled.connect(self._on_cancelled)
        self.warnings: list[str] = []
        self.worker.warned.connect(self._on_warned)
        self.worker.progress.connect(self._relay_progress)
        self.dialog = None
        self._progress = (title, 0, 0)  # the latest (stage, done, total), shown once the dialog opens
        from app.models.task_status import ProgressEstimate

        self.estimate = ProgressEstimate()  # the time left, said in the dialog
        if dialog:
            self.dialog = QtWidgets.QProgressDialog(title, "Cancel", 0, 0, parent if isinstance(
                parent, QtWidgets.QWidget) else None)
            self.dialog.setWindowTitle("Lipspace")
            self.dialog.setAutoClose(False)
            self.dialog.setAutoReset(False)
            self.dialog.setWindowModality(QtCore.Qt.WindowModality.WindowModal)
            self.dialog.canceled.connect(self.cancel)
            self.dialog.reset()  # Qt's own show-after-minimumDuration timer is never started: _show_dialog
            self._show_timer = QtCore.QTimer(self)
            self._show_timer.setSingleShot(True)
            self._show_timer.setInterval(DIALOG_DELAY_MS)
            self._show_timer.timeout.connect(self._show_dialog)
            self._tick = QtCore.QTimer(self)  # the dialog's label lives between reports: seconds, time left
            self._tick.setInterval(1000)
            self._tick.timeout.connect(lambda: self._on_progress(*self._progress))

    def start(self, *, after_events: bool = False) -> TaskRunner:
        """Start the worker thread; ``after_events``: at the GUI event loop's next turn, once the events
        waiting now (a redraw of what was just shown) are handled. Until then the task counts as
        running; cancelled before it starts, it ends cancelled at its first progress report."""
        WARNINGS.install()
        if after_events:
            QtCore.QTimer.singleShot(0, self, self.thread.start)
        else:
            self.thread.start()
        if self.dialog is not None:
            self._show_timer.start()
        return self

    def cancel(self) -> None:
        self.worker.cancel()
        if self.dialog is not None:
            self.dialog.setLabelText("Cancelling…")

    def _relay_progress(self, stage, done, total):
        self._on_progress(stage, done, total)
        self.progressed.emit(stage, done, total)

    def _on_progress(self, stage, done, total):
        """Keep the latest progress; the dialog shows it once it is open. A modal QProgressDialog's
        ``setValue`` processes events (a repaint of the whole window, ~20 ms in software GL), so a
        task done within :data:`DIALOG_DELAY_MS` never touches it."""
        self._progress = (stage, done, total)
        self.estimate.report(stage, done, total)
        d = self.dialog
        if d is None or self.worker.cancel_requested or not d.isVisible():
            return
        if total > 0 and done < total:
            d.setMaximum(total)
            d.setValue(done)
        else:  # no total, or the count complete while the stage works on: busy, not frozen at 100 %
            d.setMaximum(0)
        d.setLabelText(self.estimate.text())

    def _show_dialog(self) -> None:
        """The task has run :data:`DIALOG_DELAY_MS`: open the progress dialog at its latest progress."""
        if self.state != "running" or self.dialog is None or self.worker.cancel_requested:
            return
        self.dialog.show()
        self._tick.start()
        self._on_progress(*self._progress)

    def _on_warned(self, message):
        self.warnings.append(message)
        self.warned.emit(message)

    def _finish(self, state):
        self.state = state
        self.thread.quit()
        self.thread.wait()
        if self.dialog is not None:
            self._show_timer.stop()
            self._tick.stop()
            # reset() also stops the dialog's own show-after-minimumDuration timer (started by a
            # setValue): a task done sooner would otherwise get its dialog shown after this close
            self.dialog.reset()
            self.dialog.close()

    def _on_done(self, result):
        self.result = result
        self._finish("done")
        self.finished.emit(result)

    def _on_failed(self, message, tb):
        self.error = (message, tb)
        self._finish("failed")
        self.failed.emit(message, tb)

    def _on_cancelled(self):
        self._finish("cancelled")
        self.cancelled.emit()

    def wait(self, timeout_ms: int | None = None) -> bool:
        """Process events until the task ends (for scripts and tests); returns True if it ended."""
        timer = QtCore.QElapsedTimer()
        timer.start()
        app = QtWidgets.QApplication.instance()
        while self.state == "running":
            app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 50)
            if timeout_ms is not None and timer.elapsed() > timeout_ms:
                return False
        return True


def run_task(task, *, parent=None, title: str = "Working", on_done=None, on_error=None, on_cancel=None,
             dialog: bool = True, after_events: bool = False) -> TaskRunner:
    """Start ``task(progress)`` in a worker thread with a progress dialog; returns the runner.

    ``on_done(result)``, ``on_error(message, traceback)`` and ``on_cancel()`` run on the
    GUI thread. Without ``on_error`` a failure is shown in a message box. ``after_events``: the
    thread starts at the event loop's next turn (:meth:`TaskRunner.start`).
    """
    runner = _kept(TaskRunner(task, parent=parent, title=title, dialog=dialog))
    connect_outcome(runner, parent=parent, on_done=on_done, on_error=on_error, on_cancel=on_cancel)
    return runner.start(after_events=after_events)


def start_task(task, *, title: str = "Working") -> TaskRunner:
    """Start ``task(progress)`` in a worker thread now, before the window that shows its outcome exists
    (no dialog); that window takes it over with :func:`connect_outcome`."""
    return _kept(TaskRunner(task, title=title, dialog=False)).start()


def connect_outcome(runner: TaskRunner, *, parent=None, on_done=None, on_error=None, on_cancel=None) -> TaskRunner:
    """Send ``runner``'s outcome to ``on_done(result)`` / ``on_error(message, traceback)`` / ``on_cancel()``
    on the GUI thread (without ``on_error`` a failure is shown in a message box), and its data warnings to
    ``parent``'s status bar when ``parent`` is a main window. A runner started before its window
    (:func:`start_task`) that has ended already sends its outcome again at the event loop's next turn,
    to everything connected by then."""
    if on_error is None:
        def on_error(msg, _tb):
            QtWidgets.QMessageBox.critical(parent if isinstance(parent, QtWidgets.QWidget) else None, "Lipspace", msg)
    for signal, handler in ((runner.finished, on_done), (runner.failed, on_error), (runner.cancelled, on_cancel)):
        if handler is not None:
            signal.connect(handler)
    if isinstance(parent, QtWidgets.QMainWindow):
        def warn(msg):
            parent.statusBar().showMessage(f"warning: {msg}", 15000)

        runner.warned.connect(warn)
        for msg in runner.warnings[-1:]:  # warned before the window took the task over
            warn(msg)
    if parent is not None and runner.parent() is None:
        runner.setParent(parent)
    if runner.state == "done":
        QtCore.QTimer.singleShot(0, lambda: runner.finished.emit(runner.result))
    elif runner.state == "failed":
        QtCore.QTimer.singleShot(0, lambda: runner.failed.emit(*runner.error))
    elif runner.state == "cancelled":
        QtCore.QTimer.singleShot(0, runner.cancelled.emit)
    return runner


def _kept(runner: TaskRunner) -> TaskRunner:
    """Keep ``runner`` alive while it runs (a Qt object without a parent would be collected)."""
    _RUNNING.add(runner)
    for sig in (runner.finished, runner.failed, runner.cancelled):
        sig.connect(lambda *_a, r=runner: _RUNNING.discard(r))
    return runner


_RUNNING: set = set()


def running() -> bool:
    """Whether a task's thread still runs (cancelled or not: a task stops at its next progress call)."""
    return any(r.thread.isRunning() for r in list(_RUNNING))


def exit_if_tasks_run(code: int, *, wait_s: float = 60.0) -> None:
    """End the process now with ``code`` when a task's thread still runs after the window closed.

    A task cancelled inside a long engine step (the method choice's validation, the gestures of a
    large corpus) stops only at its next progress call, and Qt aborts the process (a core dump,
    "QThread: Destroyed while thread is still running") when the interpreter exits first. Called
    after the event loop: everything the window keeps is written by then (the settings, the
    autosave); the other non-daemon threads (a cache file being written) get ``wait_s`` seconds to
    finish, and the output streams are flushed. Returns when no task runs.
    """
    import contextlib
    import os
    import sys
    import threading
    import time

    if not running():
        return
    end = time.monotonic() + wait_s
    for t in threading.enumerate():
        if t is not threading.current_thread() and not t.daemon and not isinstance(t, threading._DummyThread):
            t.join(max(0.0, end - time.monotonic()))
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError, AttributeError):
            stream.flush()
    os._exit(code)


def cancel_all(timeout_ms: int = 5000) -> None:
    """Cancel every task started by :func:`run_task` and wait for their threads (on quit)."""
    for r in list(_RUNNING):
        r.cancel()
    for r in list(_RUNNING):
        r.thread.quit()
        r.thread.wait(timeout_ms)


def run_blocking(task, *, parent=None, title: str = "Working"):
    """Run ``task(progress)`` in a worker with a progress dialog and wait for it (GUI responsive).

    Returns the result; raises :class:`Cancelled` if the user cancelled and
    RuntimeError with the task's message if it failed.
    """
    runner = TaskRunner(task, parent=parent, title=title).start()
    runner.wait()
    if runner.state == "cancelled":
        raise Cancelled("cancelled by the user")
    if runner.state == "failed":
        raise RuntimeError(runner.error[0])
    return runner.result

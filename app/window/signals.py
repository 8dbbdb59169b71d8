"""Stopping the explorer from its terminal or the desktop session: Ctrl-C, SIGTERM, SIGHUP."""
from __future__ import annotations

import contextlib
import signal
import threading

from PySide6 import QtCore, QtWidgets

__all__ = ["stop_on_signals", "STOP_SIGNALS", "SIGNAL_POLL_MS"]

#: signals that stop the explorer from its terminal or the desktop session (Ctrl-C, kill, logout)
STOP_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")
#: how often the event loop hands control to Python so that a stop signal's handler runs (ms)
SIGNAL_POLL_MS = 200


@contextlib.contextmanager
def stop_on_signals(app, win):
    """Ctrl-C in the terminal, SIGTERM or SIGHUP close ``win`` as File > Quit does and end the loop.

    Python runs a signal handler only between its own bytecodes, and the Qt event loop
    runs none while it waits: a timer hands control to Python every ``SIGNAL_POLL_MS``.
    The handler only notes the signal; the timer's slot saves the session to the
    autosave (when there is one and something is loaded), closes the window and quits,
    from the event loop, never from inside whatever slot the signal interrupted.
    Without this the command-line handler's ``KeyboardInterrupt`` was raised inside a
    Qt slot, printed as a traceback and swallowed: the window could not be stopped.

    Yields the list of signal names received (empty unless one stopped the window).
    Only in the main thread; the previous handlers are restored on exit.
    """
    stopped: list = []
    if threading.current_thread() is not threading.main_thread():
        yield stopped
        return

    def handler(signum, _frame):
        stopped.append(signal.Signals(signum).name)

    def poll():
        if not stopped or poll.done:
            return
        poll.done = True
        modal = QtWidgets.QApplication.activeModalWidget()
        if isinstance(modal, QtWidgets.QDialog):  # the restore question (or any dialog): answered "not now"
            modal.reject()
        a = win.autosaver
        if a is not None and win.state.manifold is not None:
            with contextlib.suppress(OSError, ValueError, RuntimeError):
                a.save(win.save_session)
        win.close()
        app.quit()

    poll.done = False
    old = {}
    for name in STOP_SIGNALS:
        sig = getattr(signal, name, None)
        if sig is not None:
            old[sig] = signal.signal(sig, handler)
    timer = QtCore.QTimer()
    timer.setInterval(SIGNAL_POLL_MS)
    timer.timeout.connect(poll)
    timer.start()
    try:
        yield stopped
    finally:
        timer.stop()
        for sig, h in old.items():
            signal.signal(sig, h)

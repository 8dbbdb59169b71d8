"""Starting the explorer: the application, the autosave question, the window and its event loop.

What the window will show is loaded from the first moment it is known. When the source is known
before the window exists — a file or the synthetic talker named on the command line, or a session
file, and no dead run's autosave waiting for the restore question — its load starts in a worker
thread before the window's own imports (Qt's widgets, VTK, pyvista) and construction, which take
about as long as the load, and the window takes the running load over
(:meth:`app.main_window.MainWindow.open_source` with ``started``): its status bar shows it, Cancel
stops it. When the restore question decides the source, the load starts after the answer, as the
window opens.
"""
from __future__ import annotations

import contextlib
import signal
import sys

from PySide6 import QtWidgets

from app.window.signals import stop_on_signals

__all__ = ["launch", "ask_restore", "opened_source"]


def ask_restore(recovery, parent=None) -> str:
    """Ask whether to reopen a crashed run's autosave: "restore", "discard" or "later"."""
    box = QtWidgets.QMessageBox(parent)
    box.setIcon(QtWidgets.QMessageBox.Icon.Question)
    box.setWindowTitle("Lipspace")
    box.setText(recovery.describe())
    box.setInformativeText("Restore that session now?")
    yes = box.addButton("Restore", QtWidgets.QMessageBox.ButtonRole.AcceptRole)
    no = box.addButton("Discard", QtWidgets.QMessageBox.ButtonRole.DestructiveRole)
    box.addButton("Not now", QtWidgets.QMessageBox.ButtonRole.RejectRole)
    box.setDefaultButton(yes)
    box.exec()
    clicked = box.clickedButton()
    return "restore" if clicked is yes else "discard" if clicked is no else "later"


def opened_source(session: dict | None, path=None, preset: str = "default",
                  kinematics: str = "classic") -> tuple:
    """``(path, preset, kinematics)`` the window opens: a session's source replaces the command line's
    when no file is named (a session's file is its own frames: classic kinematics)."""
    from app.files.session import source_kinematics

    if session is None or path is not None:
        return path, preset, kinematics
    src = session.get("source", {})
    if src.get("path"):
        return src["path"], src.get("preset", preset), "classic"
    return None, src.get("preset", preset), source_kinematics(session)


def _start_loading(source):
    """The load of ``source`` started in a worker thread (None for a source the window will refuse)."""
    from app.files.source_loading import loading_task
    from app.workers import start_task

    try:
        what, task = loading_task(*source)
    except ValueError:  # a kinematics the window reports when it opens the source
        return None
    return start_task(task, title=f"Loading {what}")


def launch(path=None, preset: str = "default", session: dict | None = None, restore: bool | None = None, *,
           kinematics: str = "classic", notes=()) -> int:
    """Open the explorer on ``path`` (or the synthetic talker ``preset`` with ``kinematics``)
    and run the event loop; a session's (or a restored autosave's) source overrides them.

    ``restore`` answers the autosave question after an abnormal exit (None: ask in a
    dialog); see :mod:`app.files.autosave`. Damaged state files (autosave markers and sessions,
    the window settings) are moved aside and said, on stderr and in one dialog, with
    ``notes`` (e.g. a --session file that could not be opened); the window opens anyway.
    The source's load starts before the window is built when nothing is to be asked first.
    """
    from app.files.autosave import Autosaver, resolve_recovery
    from app.files.session import SessionError
    from app.qt_app import make_application
    from app.user_messages import user_message
    from app.workers import cancel_all

    app = make_application(sys.argv[:1])
    autosaver = Autosaver()
    try:
        recovery = autosaver.begin()
    except OSError as exc:
        print(f"lipspace explore: warning: autosave is off ({autosaver.directory}: {exc})", file=sys.stderr)
        autosaver, recovery = None, None
    early = None
    if session is not None or autosaver is None or recovery is None or restore is False:  # nothing to ask
        early_source = opened_source(session, path, preset, kinematics)
        early = _start_loading(early_source)
    try:
        from app.main_window import MainWindow  # the window's imports: Qt's widgets, VTK, pyvista

        win = MainWindow(autosave=autosaver)
    except BaseException:
        cancel_all()  # a load started above must not outlive the interpreter (Qt aborts then)
        raise
    signals = contextlib.ExitStack()  # from here on (the restore question too) a stop signal closes the window
    stopped = signals.enter_context(stop_on_signals(app, win))
    win.show()
    said = list(notes)
    for note in (autosaver.set_aside if autosaver is not None else []) + win.settings.set_aside:
        print(f"lipspace explore: warning: {note}", file=sys.stderr)
        said.append(note)
    if said:
        win.show_error("\n\n".join(said))
    if autosaver is not None and session is None:
        try:
            restored = resolve_recovery(autosaver, recovery, restore=restore, ask=lambda r: ask_restore(r, win))
        except SessionError as exc:
            print(f"lipspace explore: warning: {exc}", file=sys.stderr)
            win.show_error(user_message(exc, doing="restore the autosaved session"))  # not modal: the window runs
            restored = None
        if restored is not None:
            session, path = restored, None
    path, preset, kinematics = opened_source(session, path, preset, kinematics)
    if early is not None and early_source != (path, preset, kinematics):
        early.cancel()
        early = None
    code = 0
    if not stopped:  # else a signal came during the restore question: the window is closed already
        win.open_source(path, preset=preset, kinematics=kinematics, session=session, started=early)
        code = int(app.exec())
    signals.close()
    if stopped:
        # not a chosen Quit: no finish(), so a saved session (or a restored one not yet saved
        # again) stays and the next start offers it back; a marker without one is pruned then
        if autosaver is not None and autosaver.session.is_file():
            kept = "the session was autosaved and is offered back at the next start"
        else:
            kept = "nothing was autosaved yet" if autosaver is not None else "autosave is off"
        print(f"lipspace explore: stopped by {stopped[-1]}; the window was closed ({kept}).", file=sys.stderr)
        return 128 + int(getattr(signal, stopped[-1]))
    if autosaver is not None:
        autosaver.finish()  # a clean exit: nothing to offer next time
    return code


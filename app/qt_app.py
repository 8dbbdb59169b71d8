"""The explorer's QApplication, with a quiet console.

Qt Multimedia (the lip view's audio) logs what it probes at start-up under the
``qt.multimedia.*`` categories ("Couldn't load pipewire-0.3 library", "Using Qt
multimedia with FFmpeg ...") and its PulseAudio back-end warns without a category
when no sound server runs ("PulseAudioService: pa_context_connect() failed"). None of
it is for the user: playback without a sound device is already handled by
:class:`app.audio.AudioPlayer`. :func:`quiet_qt_messages` switches those categories off
(a ``QT_LOGGING_RULES`` the user sets still takes precedence, to debug) and filters the
uncategorised PulseAudio line; every other Qt message still reaches stderr.

:func:`make_application` also brings up Qt's accessibility bridge at once, not when the first
widget is made. On Linux the bridge connects to the session's D-Bus, and without one (a virtual X
server, a remote shell) D-Bus forks to launch it, from its own thread. The window's first widget is
made while the manifold loads in a worker; a fork while that worker's BLAS threads are running
deadlocked the process (OpenBLAS joins its threads before a fork; 3 of 10 warm starts hung). Made
with the application, before any worker starts, the fork finds BLAS idle.
"""
from __future__ import annotations

import sys

from PySide6 import QtCore, QtGui, QtWidgets

__all__ = ["quiet_qt_messages", "make_application", "NOISY_CATEGORIES", "NOISY_PREFIXES"]

NOISY_CATEGORIES = ("qt.multimedia",)
NOISY_PREFIXES = ("PulseAudioService:",)
_INSTALLED = {"done": False}


def _handler(mode, context, message):
    category = context.category or ""
    if category.startswith(NOISY_CATEGORIES) or message.startswith(NOISY_PREFIXES):
        return
    sys.stderr.write(QtCore.qFormatLogMessage(mode, context, message) + "\n")


def quiet_qt_messages() -> None:
    """Silence Qt Multimedia's start-up chatter (idempotent; call before the QApplication)."""
    if _INSTALLED["done"]:
        return
    QtCore.QLoggingCategory.setFilterRules("\n".join(f"{c}*=false" for c in NOISY_CATEGORIES))
    QtCore.qInstallMessageHandler(_handler)
    _INSTALLED["done"] = True


def make_application(argv=None) -> QtWidgets.QApplication:
    """The running QApplication, or a new one named "Lipspace", with :func:`quiet_qt_messages` applied
    and its accessibility bridge up (call before starting worker threads)."""
    quiet_qt_messages()
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(list(argv if argv is not None
                                                                            else sys.argv[:1]))
    app.setApplicationName("Lipspace")
    app.setOrganizationName("Lipspace")
    QtGui.QAccessible.isActive()  # connects the bridge now, a D-Bus launch (a fork) included
    return app

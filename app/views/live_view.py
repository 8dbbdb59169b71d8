"""The live mirror window (``lipspace explore --manifold M --camera 0|video.mp4``).

A camera (or a video file played as a stream) is read, tracked and projected into a
built manifold in background threads (:class:`app.models.live.LiveSession`); a 30 Hz timer
takes what was projected, extends the live trajectory, moves the marker, recolours the
states by the current state's future hemisphere (:class:`app.views.live_scene.LiveScene`)
and shows the counters: frames processed, received, dropped (when tracking cannot keep
up with the stream) and without a face.
"""
from __future__ import annotations

import sys

from PySide6 import QtCore, QtWidgets

from app.models.live import LiveSession
from app.views._common import RenderScheduler, close_plotter, make_plotter
from app.views.live_scene import LiveScene

__all__ = ["LiveWindow", "launch_live"]

POLL_MS = 33


class LiveWindow(QtWidgets.QMainWindow):
    """Shows one :class:`LiveSession` (started by the caller) over its manifold."""

    def __init__(self, session: LiveSession, parent=None):
        super().__init__(parent)
        self.session = session
        self.setWindowTitle(f"Lipspace live mirror: {session.url}")
        self.plotter = make_plotter(self)
        self.setCentralWidget(self.plotter.interactor)
        self.status = QtWidgets.QLabel("live: starting")
        self.statusBar().addPermanentWidget(self.status, 1)
        self.scene = LiveScene(self.plotter, session.manifold, rate=session.rate or 30.0)
        self.renders = RenderScheduler(self.plotter)
        self.renders.request()
        self.timer = QtCore.QTimer(self)
        self.timer.setInterval(POLL_MS)
        self.timer.timeout.connect(self.poll)
        self.timer.start()
        self.last_stats = None
        self._reported = False
        self.resize(900, 700)

    def poll(self) -> None:
        samples, stats = self.session.poll()
        if self.scene.update(samples, self.session.projector.future):
            self.renders.request()
        self.status.setText(stats.line())
        self.last_stats = stats
        if stats.error and not self._reported:
            self._reported = True
            QtWidgets.QMessageBox.warning(self, "Lipspace live mirror", stats.error)

    def closeEvent(self, event) -> None:  # noqa: N802 - Qt name
        self.timer.stop()
        self.session.stop()
        self.renders.stop()
        close_plotter(self.plotter)
        super().closeEvent(event)


def launch_live(manifold, source, *, interocular_mm: float = 63.0) -> int:
    """Open the live mirror on a loaded ``manifold`` and a camera number / video file; run the event loop."""
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    app.setApplicationName("Lipspace")
    session = LiveSession(manifold, source, interocular_mm=interocular_mm).start()
    win = LiveWindow(session)
    win.show()
    return int(app.exec())

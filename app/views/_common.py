"""Small Qt helpers shared by the views."""
from __future__ import annotations

from contextlib import contextmanager

__all__ = ["blocked", "make_plotter", "camera_of", "set_camera", "close_plotter", "connect_all", "disconnect_all"]


@contextmanager
def blocked(*widgets):
    """Block the Qt signals of ``widgets`` while syncing them to the state."""
    old = [w.blockSignals(True) for w in widgets]
    try:
        yield
    finally:
        for w, o in zip(widgets, old):
            w.blockSignals(o)


def make_plotter(parent):
    """A pyvistaqt QtInteractor with the explorer's look (white background, paper style)."""
    from pyvistaqt import QtInteractor

    # no auto-update timer: views render on demand (RenderScheduler), so an idle window costs nothing
    plotter = QtInteractor(parent, auto_update=False)
    plotter.set_background("white")
    return plotter


def camera_of(plotter) -> list:
    """The camera as [[position], [focal point], [view up]] (JSON-ready)."""
    return [[float(x) for x in row] for row in plotter.camera_position]


def set_camera(plotter, cam) -> None:
    """Restore a camera saved by :func:`camera_of` (ignored when malformed)."""
    try:
        rows = [[float(x) for x in row] for row in cam]
    except (TypeError, ValueError):
        return
    if len(rows) == 3 and all(len(r) == 3 for r in rows):
        plotter.camera_position = rows
        plotter.render()


def close_plotter(plotter) -> None:
    """Close a QtInteractor's render window (safe to call twice)."""
    if not getattr(plotter, "_lipspace_closed", False):
        plotter._lipspace_closed = True
        plotter.close()


class RenderScheduler:
    """Coalesce render requests: many state events in one pass give one render.

    ``request()`` schedules ``plotter.render()`` on the next turn of the Qt event
    loop; ``flush()`` renders now if one is pending.
    """

    def __init__(self, plotter):
        from PySide6 import QtCore

        self.plotter = plotter
        self.pending = False
        self._timer = QtCore.QTimer()
        self._timer.setSingleShot(True)
        self._timer.setInterval(0)
        self._timer.timeout.connect(self.flush)

    def request(self) -> None:
        if not self.pending:
            self.pending = True
            self._timer.start()

    def flush(self) -> None:
        if self.pending:
            self.pending = False
            if not getattr(self.plotter, "_lipspace_closed", False):
                self.plotter.render()

    def stop(self) -> None:
        self._timer.stop()
        self.pending = False


def connect_all(connections) -> list:
    """Connect each ``(event, callback)`` pair of a view to the state; returns the list."""
    connections = list(connections)
    for event, cb in connections:
        event.connect(cb)
    return connections


def disconnect_all(connections) -> None:
    """Undo :func:`connect_all` (pairs already gone are skipped)."""
    for event, cb in connections:
        try:
            event.disconnect(cb)
        except ValueError:
            pass

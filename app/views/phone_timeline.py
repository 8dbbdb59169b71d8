"""The trajectory editor's timeline: phone intervals, draggable key targets, a time axis in ms, a playback cursor.

Drawing and input only; what an edit means (undo, synthesis) is the editor's
(:mod:`app.views.trajectory_editor`), the arithmetic of moving a target is
:mod:`app.models.target_editing`'s.
"""
from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from app.models.target_editing import move_target, time_ticks

__all__ = ["PhoneTimeline"]


class PhoneTimeline(QtWidgets.QWidget):
    """Phone intervals as boxes, targets as draggable triangles, time ticks in ms, the playback position as a line.

    Signals
    -------
    targetsChanged(before, after)
        A drag ended with a target on another frame (both TargetSequences).
    selectionChanged(index or None)
        The chosen target (clicked) changed.
    playToggled(), stepRequested(int), deleteRequested()
        Space, Left / Right, Delete / Backspace while the timeline has the focus.
    zoomRequested(factor, x)
        Wheel or + / - keys: zoom by ``factor`` keeping pixel ``x`` in place.
    """

    targetsChanged = QtCore.Signal(object, object)
    selectionChanged = QtCore.Signal(object)
    playToggled = QtCore.Signal()
    stepRequested = QtCore.Signal(int)
    deleteRequested = QtCore.Signal()
    zoomRequested = QtCore.Signal(float, float)
    MARGIN = 8
    GRAB = 7
    HEIGHT = 96

    def __init__(self, parent=None):
        super().__init__(parent)
        self.targets = None
        self.cursor = None
        self.selected = None
        self._drag = None
        self._drag_start = None
        self.setMinimumHeight(self.HEIGHT)
        self.setMouseTracking(True)
        self.setFocusPolicy(QtCore.Qt.FocusPolicy.StrongFocus)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Fixed, QtWidgets.QSizePolicy.Policy.Fixed)

    def set_targets(self, targets) -> None:
        self.targets = targets
        self._drag = None
        if self.selected is not None and (targets is None or self.selected >= len(targets.targets)):
            self.select(None)
        self.update()

    def set_cursor(self, frame) -> None:
        self.cursor = frame
        self.update()

    def select(self, index) -> None:
        if index != self.selected:
            self.selected = index
            self.selectionChanged.emit(index)
        self.update()

    # geometry
    def _x(self, frame: float) -> float:
        n = max(self.targets.n_frames - 1, 1)
        return self.MARGIN + (self.width() - 2 * self.MARGIN) * frame / n

    def frame_at(self, x: float) -> float:
        """Frame (fractional) under pixel ``x``."""
        n = max(self.targets.n_frames - 1, 1) if self.targets is not None else 1
        return (x - self.MARGIN) / max(self.width() - 2 * self.MARGIN, 1) * n

    def marker_x(self, index: int) -> float:
        """Pixel x of target ``index`` (for tests and tools)."""
        return self._x(self.targets.targets[index].frame)

    def marker_y(self) -> float:
        return self.height() - 12

    def ticks(self) -> tuple[int, list[int]]:
        """(step, tick times) of the time axis in ms, for the current width."""
        t = self.targets
        if t is None:
            return 0, []
        return time_ticks(0.0, 1000.0 * (t.n_frames - 1) / t.rate, self.width() - 2 * self.MARGIN)

    def paintEvent(self, _event):
        qp = QtGui.QPainter(self)
        qp.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing)
        qp.fillRect(self.rect(), QtGui.QColor("white"))
        if self.targets is None:
            qp.setPen(QtGui.QColor("gray"))
            qp.drawText(self.rect(), QtCore.Qt.AlignmentFlag.AlignCenter, "no targets: choose an input and press Load")
            return
        t = self.targets
        h = self.height()
        top, box_h = 4, h - 56
        for i, p in enumerate(t.phones):
            x0, x1 = self._x(p.start * t.rate), self._x(p.end * t.rate)
            qp.fillRect(QtCore.QRectF(x0, top, max(x1 - x0, 1), box_h),
                        QtGui.QColor("#e8e8f0" if i % 2 else "#d4d8e8"))
            qp.setPen(QtGui.QColor("#222"))
            qp.drawText(QtCore.QRectF(x0, top, max(x1 - x0, 1), box_h), QtCore.Qt.AlignmentFlag.AlignCenter, p.label)
        # time axis, ticks in ms
        y_axis = top + box_h + 2
        qp.setPen(QtGui.QColor("#888"))
        qp.drawLine(QtCore.QPointF(self.MARGIN, y_axis), QtCore.QPointF(self.width() - self.MARGIN, y_axis))
        step, ticks = self.ticks()
        font = qp.font()
        font.setPointSizeF(max(font.pointSizeF() - 1.5, 6.0))
        qp.setFont(font)
        for ms in ticks:
            x = self._x(ms / 1000.0 * t.rate)
            qp.drawLine(QtCore.QPointF(x, y_axis), QtCore.QPointF(x, y_axis + 4))
            qp.drawText(QtCore.QRectF(x - 40, y_axis + 4, 80, 14), QtCore.Qt.AlignmentFlag.AlignHCenter,
                        f"{ms} ms" if ms == ticks[-1] or ms == 0 else f"{ms}")
        # targets
        ym = self.marker_y()
        for i, tg in enumerate(t.targets):
            x = self._x(tg.frame)
            col = QtGui.QColor("#ff7f00" if i == self._drag else "#1f5fbf" if i == self.selected else "#c00000")
            qp.setPen(QtGui.QPen(col, 1, QtCore.Qt.PenStyle.DashLine))
            qp.drawLine(QtCore.QPointF(x, top), QtCore.QPointF(x, ym - 6))
            qp.setPen(QtCore.Qt.PenStyle.NoPen)
            qp.setBrush(col)
            qp.drawPolygon(QtGui.QPolygonF([QtCore.QPointF(x, ym - 6), QtCore.QPointF(x - 6, ym + 6),
                                            QtCore.QPointF(x + 6, ym + 6)]))
        if self.cursor is not None:
            qp.setPen(QtGui.QPen(QtGui.QColor("black"), 2))
            x = self._x(self.cursor)
            qp.drawLine(QtCore.QPointF(x, 0), QtCore.QPointF(x, h))
        qp.end()

    # input
    def _hit(self, pos) -> int | None:
        if self.targets is None or abs(pos.y() - self.marker_y()) > 12:
            return None
        xs = np.array([self._x(tg.frame) for tg in self.targets.targets])
        if xs.size == 0:
            return None
        i = int(np.argmin(np.abs(xs - pos.x())))
        return i if abs(xs[i] - pos.x()) <= self.GRAB else None

    def mousePressEvent(self, ev):
        self.setFocus(QtCore.Qt.FocusReason.MouseFocusReason)
        self._drag = self._hit(ev.position())
        self._drag_start = self.targets
        if self._drag is not None:
            self.select(self._drag)
        self.update()

    def mouseMoveEvent(self, ev):
        if self._drag is None:
            self.setCursor(QtCore.Qt.CursorShape.SizeHorCursor if self._hit(ev.position()) is not None
                           else QtCore.Qt.CursorShape.ArrowCursor)
            return
        self.targets = move_target(self.targets, self._drag, int(round(self.frame_at(ev.position().x()))))
        self.update()

    def mouseReleaseEvent(self, ev):
        if self._drag is not None:
            i, self._drag = self._drag, None
            self.update()
            before = self._drag_start
            if before is not None and before.targets[i].frame != self.targets.targets[i].frame:
                self.targetsChanged.emit(before, self.targets)

    def wheelEvent(self, ev):
        steps = ev.angleDelta().y() / 120.0
        if steps:
            self.zoomRequested.emit(1.25 ** steps, ev.position().x())
        ev.accept()

    def keyPressEvent(self, ev):
        k = ev.key()
        Key = QtCore.Qt.Key
        if k == Key.Key_Space:
            self.playToggled.emit()
        elif k in (Key.Key_Left, Key.Key_Right):
            self.stepRequested.emit(-1 if k == Key.Key_Left else 1)
        elif k in (Key.Key_Delete, Key.Key_Backspace):
            self.deleteRequested.emit()
        elif k in (Key.Key_Plus, Key.Key_Equal, Key.Key_Minus):
            x = self._x(self.cursor) if (self.cursor is not None and self.targets is not None) else self.width() / 2
            self.zoomRequested.emit(0.8 if k == Key.Key_Minus else 1.25, x)
        else:
            super().keyPressEvent(ev)
            return
        ev.accept()

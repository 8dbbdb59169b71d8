"""A row of the editor's time strip under the tiers: the timeline's time axis, cursor, selection and keys.

The tiers (:class:`app.views.phone_timeline.PhoneTimeline`), the sound and the rows under them
share one scrolled strip; a row maps frames to pixels exactly as the timeline does (same
margin, same width: the editor sizes every row), shows the same cursor and time selection,
and sends the same time input: a click or a drag over time as ``pressed`` / ``dragged`` /
``released``, Praat's keys (:class:`app.views.phone_timeline.TimeKeys`) as ``keyCommand``,
Space as ``playToggled``. Subclasses draw their content in :meth:`paint_content` and may take
a press first (:meth:`press_content`).
"""
from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

from app.views.phone_timeline import PhoneTimeline, TimeKeys

__all__ = ["StripRow", "SELECTION_RGBA"]

#: the time selection's shading (as the tiers and the sound draw it)
SELECTION_RGBA = (255, 150, 170, 70)


class StripRow(TimeKeys, QtWidgets.QWidget):
    """A row of the time strip (module docstring)."""

    pressed = QtCore.Signal(float, float)
    dragged = QtCore.Signal(float, float)
    released = QtCore.Signal(float, float)
    keyCommand = QtCore.Signal(str)
    playToggled = QtCore.Signal()
    MARGIN = PhoneTimeline.MARGIN

    def __init__(self, parent=None):
        super().__init__(parent)
        self.n_frames, self.rate = 1, 60.0
        self.cursor = None
        self.time_selection = None
        self._pressing = False
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Fixed, QtWidgets.QSizePolicy.Policy.Fixed)
        self.setFocusPolicy(QtCore.Qt.FocusPolicy.StrongFocus)
        self.setMouseTracking(True)

    # ------------------------------------------------------------------ the time axis
    def set_span(self, n_frames: int, rate: float) -> None:
        """The timeline's frames: their count and rate."""
        self.n_frames, self.rate = max(int(n_frames), 1), float(rate)
        self.update()

    def frame_x(self, frame: float) -> float:
        """Pixel x of frame ``frame`` (the timeline's mapping)."""
        n = max(self.n_frames - 1, 1)
        return self.MARGIN + (self.width() - 2 * self.MARGIN) * float(frame) / n

    def time_x(self, t: float) -> float:
        """Pixel x of ``t`` seconds from the utterance's first frame."""
        return self.frame_x(t * self.rate)

    def frame_at(self, x: float) -> float:
        n = max(self.n_frames - 1, 1)
        return (x - self.MARGIN) / max(self.width() - 2 * self.MARGIN, 1) * n

    def x_time(self, x: float) -> float:
        return self.frame_at(x) / self.rate

    def set_cursor(self, frame) -> None:
        self.cursor = frame
        self.update()

    def set_time_selection(self, span) -> None:
        self.time_selection = None if span is None else (min(span), max(span))
        self.update()

    # ------------------------------------------------------------------ painting
    def paintEvent(self, event):
        qp = QtGui.QPainter(self)
        qp.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing)
        qp.fillRect(event.rect(), QtGui.QColor("white"))
        self.paint_content(qp)
        if self.time_selection is not None:
            a, b = self.time_selection
            qp.fillRect(QtCore.QRectF(self.frame_x(a), 0, max(self.frame_x(b) - self.frame_x(a), 1.0), self.height()),
                        QtGui.QColor(*SELECTION_RGBA))
        if self.cursor is not None:
            qp.setPen(QtGui.QPen(QtGui.QColor("black"), 2))
            x = self.frame_x(self.cursor)
            qp.drawLine(QtCore.QPointF(x, 0), QtCore.QPointF(x, self.height()))
        qp.end()

    def paint_content(self, qp) -> None:  # pragma: no cover - subclasses draw
        pass

    def small_font(self, qp, smaller: float = 1.5) -> None:
        font = qp.font()
        font.setPointSizeF(max(font.pointSizeF() - smaller, 6.0))
        qp.setFont(font)

    # ------------------------------------------------------------------ input
    def press_content(self, ev) -> bool:
        """Take a press before it becomes time input (True: taken)."""
        return False

    def mousePressEvent(self, ev):
        self.setFocus(QtCore.Qt.FocusReason.MouseFocusReason)
        if self.press_content(ev):
            return
        if ev.button() == QtCore.Qt.MouseButton.LeftButton:
            self._pressing = True
            self.pressed.emit(self.frame_at(ev.position().x()), ev.position().x())

    def mouseMoveEvent(self, ev):
        if self._pressing:
            self.dragged.emit(self.frame_at(ev.position().x()), ev.position().x())

    def mouseReleaseEvent(self, ev):
        if self._pressing:
            self._pressing = False
            self.released.emit(self.frame_at(ev.position().x()), ev.position().x())

    def keyPressEvent(self, ev):
        if ev.key() == QtCore.Qt.Key.Key_Space:
            self.playToggled.emit()
            ev.accept()
            return
        super().keyPressEvent(ev)

"""Derived signals as channels under the editor's timeline, as mview's and VisArtico's displays stack them.

Drawing and the strip's time input only (:class:`app.views.strip_row.StripRow`): one row per
channel of :meth:`app.models.tracks.TrackPanel.view` (lip aperture, protrusion, a sensor's
tangential velocity, its position along the talker's axes, its rms), each on the y-range the
panel fixes over the corpus (so a channel's scale never jumps between utterances), named with
its unit; gaps (NaN) break the line; the gestural landmarks of the track they were found on
are dots on its curve in their palette colours. Hovering reads the channel out at the pointer.
"""
from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from app.views.strip_row import StripRow

__all__ = ["TrackChannels"]


class TrackChannels(StripRow):
    """The channels of one utterance (module docstring)."""

    #: a channel row's height, and on a small screen (:meth:`set_compact`)
    ROW_H, COMPACT_ROW_H = 52, 34
    PAD = 4

    def __init__(self, parent=None):
        super().__init__(parent)
        self.view = None  # app.models.tracks.TrackView
        self.message = ""
        self.marks: dict = {}  # channel name -> [(t s, (r, g, b), label)]
        self.row_h = self.ROW_H
        self.setFixedHeight(1)

    # ------------------------------------------------------------------ data
    def set_view(self, view, message: str = "") -> None:
        """Show ``view`` (a :class:`app.models.tracks.TrackView`; None: ``message`` instead)."""
        self.view, self.message = view, message
        self.setFixedHeight(self.wanted_height())
        self.update()

    def set_marks(self, marks: dict) -> None:
        """Dots on channels: ``{channel: [(t s, rgb, label), ...]}``."""
        self.marks = dict(marks)
        self.update()

    def set_compact(self, on: bool) -> None:
        self.row_h = self.COMPACT_ROW_H if on else self.ROW_H
        self.setFixedHeight(self.wanted_height())
        self.update()

    @property
    def names(self) -> list[str]:
        return [] if self.view is None else [c.name for c in self.view.channels]

    def wanted_height(self) -> int:
        """The rows' height (one row for a message; 0 with nothing to show)."""
        if self.view is not None and self.view.channels:
            return self.row_h * len(self.view.channels)
        return self.row_h if self.message else 0

    def row_rect(self, k: int) -> QtCore.QRectF:
        return QtCore.QRectF(0, k * self.row_h, self.width(), self.row_h)

    def value_y(self, k: int, value: float) -> float:
        """Pixel y of ``value`` in channel ``k``'s row (its fixed y-range)."""
        lo, hi = self.view.channels[k].y_range
        top = k * self.row_h + self.PAD
        h = self.row_h - 2 * self.PAD
        return top + h * (1.0 - (float(value) - lo) / (hi - lo if hi > lo else 1.0))

    def channel_at(self, y: float) -> int | None:
        k = int(y // self.row_h)
        return k if self.view is not None and 0 <= k < len(self.view.channels) else None

    # ------------------------------------------------------------------ painting
    def paint_content(self, qp) -> None:
        if self.view is None or not self.view.channels:
            if self.message:
                qp.setPen(QtGui.QColor("gray"))
                qp.drawText(self.rect(), QtCore.Qt.AlignmentFlag.AlignCenter, self.message)
            return
        fm_font = qp.font()
        for k, ch in enumerate(self.view.channels):
            rect = self.row_rect(k)
            qp.fillRect(rect, QtGui.QColor("#fbfbfd" if k % 2 else "white"))
            qp.setPen(QtGui.QPen(QtGui.QColor("#ccc"), 1))
            qp.drawLine(QtCore.QPointF(0, rect.bottom()), QtCore.QPointF(self.width(), rect.bottom()))
            lo, hi = ch.y_range
            if lo < 0 < hi:  # the zero line
                qp.setPen(QtGui.QPen(QtGui.QColor("#ddd"), 1, QtCore.Qt.PenStyle.DashLine))
                y0 = self.value_y(k, 0.0)
                qp.drawLine(QtCore.QPointF(self.MARGIN, y0), QtCore.QPointF(self.width() - self.MARGIN, y0))
            self._paint_curve(qp, k, ch.values)
            for t, rgb, _label in self.marks.get(ch.name, ()):
                v = np.interp(t * self.rate, np.arange(len(ch.values)), ch.values)
                if np.isfinite(v):
                    qp.setPen(QtGui.QPen(QtGui.QColor("#333"), 1))
                    qp.setBrush(QtGui.QColor.fromRgbF(*rgb))
                    qp.drawEllipse(QtCore.QPointF(self.time_x(t), self.value_y(k, v)), 3.5, 3.5)
            qp.setFont(fm_font)
            self.small_font(qp)
            name = f"{ch.name} ({ch.unit})" if ch.unit else ch.name
            text = f"{name}  {hi:.3g}" if self.row_h >= 40 else name
            w = qp.fontMetrics().horizontalAdvance(text) + 6
            label = QtCore.QRectF(self.MARGIN + 2, rect.top() + 1, w, qp.fontMetrics().height())
            qp.fillRect(label, QtGui.QColor(255, 255, 255, 210))
            qp.setPen(QtGui.QColor("#225"))
            qp.drawText(label, QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignVCenter, text)
            if self.row_h >= 40:
                low = QtCore.QRectF(self.MARGIN + 2, rect.bottom() - qp.fontMetrics().height() - 1, 80,
                                    qp.fontMetrics().height())
                qp.setPen(QtGui.QColor("#667"))
                qp.drawText(low, QtCore.Qt.AlignmentFlag.AlignLeft, f"{lo:.3g}")
            qp.setFont(fm_font)

    def _paint_curve(self, qp, k: int, values) -> None:
        v = np.asarray(values, np.float64)
        if v.size == 0:
            return
        qp.setPen(QtGui.QPen(QtGui.QColor("#1f4e9a"), 1.4))
        qp.setBrush(QtCore.Qt.BrushStyle.NoBrush)
        ok = np.isfinite(v)
        edges = np.flatnonzero(np.diff(np.r_[0, ok.astype(np.int8), 0]))
        for a, b in zip(edges[::2], edges[1::2]):  # each run of finite values: one polyline
            pts = [QtCore.QPointF(self.frame_x(i), self.value_y(k, v[i])) for i in range(a, b)]
            if len(pts) == 1:
                qp.drawPoint(pts[0])
            else:
                qp.drawPolyline(QtGui.QPolygonF(pts))

    # ------------------------------------------------------------------ readout
    def readout(self, pos) -> str:
        """What the pointer at ``pos`` reads: the channel's value at that time."""
        k = self.channel_at(pos.y())
        if k is None:
            return self.message
        ch = self.view.channels[k]
        f = int(round(self.frame_at(pos.x())))
        if not 0 <= f < len(ch.values):
            return ch.description
        v = ch.values[f]
        shown = "no value" if not np.isfinite(v) else f"{v:.4g} {ch.unit}".strip()
        return f"{ch.name} at {1000.0 * f / self.rate:.0f} ms: {shown}\n{ch.description}"

    def event(self, ev):
        if ev.type() == QtCore.QEvent.Type.ToolTip:
            QtWidgets.QToolTip.showText(ev.globalPos(), self.readout(ev.pos()) or "", self)
            return True
        return super().event(ev)

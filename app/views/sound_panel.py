"""The sound under the trajectory editor's timeline: waveform and a Praat-style wide-band spectrogram.

Drawing; the time input (a click sets the cursor, a drag selects a stretch, Praat's keys) is the
time strip's, as every row under the timeline takes it (:class:`app.views.strip_row.StripRow`).
The arrays come from :mod:`engine.phonetics.spectrogram` (computed in a worker
thread by the editor, :mod:`app.views.trajectory_editor`); this widget maps time to
pixels exactly as :class:`app.views.phone_timeline.PhoneTimeline` maps frames (same
margin, same width: the editor sizes both), so phone boundaries, targets and the
playback cursor line up with the sound at every zoom and scroll position. A cursor
move repaints two thin strips, never the whole panel; a paint draws only the exposed
part of the spectrogram image.
"""
from __future__ import annotations

import math
import time

import numpy as np
from PySide6 import QtCore, QtGui

from app.views.strip_row import StripRow

__all__ = ["SoundPanel"]


class SoundPanel(StripRow):
    """Waveform over spectrogram, time-aligned with a :class:`app.views.phone_timeline.PhoneTimeline` of the same width.

    Attributes
    ----------
    display : engine.phonetics.spectrogram.SoundDisplay or None
    shown_at : float or None
        ``time.perf_counter()`` when the spectrogram of the current sound was first
        painted (None until then): what "the spectrogram appears" means in tests and
        benchmarks.
    """

    WAVE_HEIGHT = 44
    SPEC_HEIGHT = 112
    GAP = 2
    HEIGHT = WAVE_HEIGHT + GAP + SPEC_HEIGHT
    #: waveform and spectrogram heights on a small screen (:meth:`set_compact`)
    COMPACT = (24, 60)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.display = None
        self.message = ""
        self.phones = ()
        self.shown_at = None
        self._image = None
        self._grey = None
        self._peak = 1.0
        self.setFixedHeight(self.HEIGHT)
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_OpaquePaintEvent)

    # ------------------------------------------------------------------ data
    def set_span(self, n_frames: int, rate: float, phones=()) -> None:
        """The timeline's frames (their count and rate) and phone intervals (seconds)."""
        self.n_frames, self.rate, self.phones = max(int(n_frames), 1), float(rate), tuple(phones)
        self.update()

    def set_sound(self, display, grey=None, message: str = "") -> None:
        """Show ``display`` (a :class:`engine.phonetics.spectrogram.SoundDisplay`) with its grey levels
        ``grey`` ((F, T) uint8, row 0 the lowest band); None: show ``message`` instead."""
        self.display, self.message, self.shown_at = display, message, None
        self._image = self._grey = None
        if display is not None:
            if grey is None:
                grey = display.spectrogram.grey()
            # row 0 of the image is the top of the panel: the highest frequency
            self._grey = np.ascontiguousarray(grey[::-1])
            h, w = self._grey.shape
            if w and h:
                self._image = QtGui.QImage(self._grey.data, w, h, w, QtGui.QImage.Format.Format_Grayscale8)
            peak = float(np.max(np.abs(display.samples))) if display.samples.size else 0.0
            self._peak = peak if peak > 0 else 1.0
            spec = display.spectrogram
            self.setToolTip(f"{display.source}: {display.duration:.3f} s at {display.sample_rate:g} Hz. "
                            f"Spectrogram 0–{spec.max_frequency:.0f} Hz, "
                            f"{1000 * spec.window_length:g} ms Gaussian window, "
                            f"{1000 * spec.time_step:g} ms steps, 50 dB dynamic range, +6 dB/octave pre-emphasis "
                            "(Praat's wide-band defaults)")
        else:
            self.setToolTip(message)
        self.update()

    def set_cursor(self, frame) -> None:
        """Move the playback cursor; only the strips it leaves and enters are repainted."""
        old, self.cursor = self.cursor, frame
        for f in (old, frame):
            if f is not None:
                x = self.frame_x(f)
                self.update(QtCore.QRect(int(math.floor(x)) - 2, 0, 5, self.height()))

    def set_compact(self, on: bool) -> None:
        """A lower waveform and spectrogram (a laptop's screen), or the full ones."""
        self.WAVE_HEIGHT, self.SPEC_HEIGHT = self.COMPACT if on else (SoundPanel.WAVE_HEIGHT, SoundPanel.SPEC_HEIGHT)
        self.HEIGHT = self.WAVE_HEIGHT + self.GAP + self.SPEC_HEIGHT
        self.setFixedHeight(self.HEIGHT)
        self.update()

    # ------------------------------------------------------------------ painting
    def paintEvent(self, event):
        qp = QtGui.QPainter(self)
        r = event.rect()
        qp.fillRect(r, QtGui.QColor("white"))
        d = self.display
        if d is None:
            if self.message:
                qp.setPen(QtGui.QColor("gray"))
                qp.drawText(self.rect(), QtCore.Qt.AlignmentFlag.AlignCenter, self.message)
            qp.end()
            return
        x0, x1 = max(r.left(), 0), min(r.right() + 1, self.width())
        self._paint_wave(qp, x0, x1)
        self._paint_spectrogram(qp, x0, x1)
        # phone boundaries through the sound, as in Praat's editors
        qp.setPen(QtGui.QPen(QtGui.QColor(40, 80, 200, 140), 1, QtCore.Qt.PenStyle.DotLine))
        bounds = sorted({b for p in self.phones for b in (p.start, p.end)})
        for t in bounds:
            x = self.time_x(t)
            if x0 - 1 <= x <= x1 + 1:
                qp.drawLine(QtCore.QPointF(x, 0), QtCore.QPointF(x, self.height()))
        if x0 <= self.MARGIN + 60:
            qp.setPen(QtGui.QColor("#06c"))
            font = qp.font()
            font.setPointSizeF(max(font.pointSizeF() - 2.0, 6.0))
            qp.setFont(font)
            top = self.WAVE_HEIGHT + self.GAP
            qp.drawText(QtCore.QPointF(self.MARGIN + 2, top + 10), f"{d.spectrogram.max_frequency:.0f} Hz")
            qp.drawText(QtCore.QPointF(self.MARGIN + 2, self.height() - 3), "0 Hz")
        if self.time_selection is not None:
            a, b = self.time_selection
            qp.fillRect(QtCore.QRectF(self.frame_x(a), 0, max(self.frame_x(b) - self.frame_x(a), 1.0), self.height()),
                        QtGui.QColor(255, 150, 170, 70))
        if self.cursor is not None:
            qp.setPen(QtGui.QPen(QtGui.QColor("black"), 2))
            x = self.frame_x(self.cursor)
            qp.drawLine(QtCore.QPointF(x, 0), QtCore.QPointF(x, self.height()))
        qp.end()

    def _paint_wave(self, qp, x0, x1):
        from engine.phonetics.spectrogram import waveform_envelope

        d = self.display
        h = self.WAVE_HEIGHT
        mid = 0.5 * h
        qp.setPen(QtGui.QPen(QtGui.QColor("#bbb"), 1))
        qp.drawLine(QtCore.QPointF(x0, mid), QtCore.QPointF(x1, mid))
        if x1 <= x0 or d.samples.size == 0:
            return
        px = np.arange(x0, x1 + 1, dtype=np.float64)
        t = np.array([self.x_time(x) for x in (px[0], px[-1])])
        # sample edges of each pixel column (sample k at (k + 0.5) / rate): linear in x
        edges = np.rint(np.interp(px, [px[0], px[-1]], t) * d.sample_rate).astype(np.int64)
        inside = (edges[1:] > 0) & (edges[:-1] < d.samples.size)
        if not inside.any():
            return
        lo, hi = waveform_envelope(d.samples, edges)
        scale = (0.5 * h - 2) / self._peak
        qp.setPen(QtGui.QPen(QtGui.QColor("#222"), 1))
        lines = [QtCore.QLineF(px[i] + 0.5, mid - hi[i] * scale, px[i] + 0.5, mid - lo[i] * scale + 0.01)
                 for i in np.flatnonzero(inside)]
        qp.drawLines(lines)

    def _paint_spectrogram(self, qp, x0, x1):
        img = self._image
        top = self.WAVE_HEIGHT + self.GAP
        if img is None or x1 <= x0:
            return
        spec = self.display.spectrogram
        T = img.width()
        dt = spec.time_step
        left = spec.times[0] - 0.5 * dt  # start of column 0
        ta, tb = self.x_time(x0), self.x_time(x1)
        k0 = max(int(math.floor((ta - left) / dt)), 0)
        k1 = min(int(math.ceil((tb - left) / dt)), T)
        if k1 <= k0:
            return
        xa, xb = self.time_x(left + k0 * dt), self.time_x(left + k1 * dt)
        # bands on a 0 .. max_frequency axis: band i spans its centre +- half a step
        f_lo = spec.frequencies[0] - 0.5 * spec.frequency_step
        f_hi = spec.frequencies[-1] + 0.5 * spec.frequency_step
        hz = self.SPEC_HEIGHT / spec.max_frequency
        ya, yb = top + self.SPEC_HEIGHT - f_hi * hz, top + self.SPEC_HEIGHT - f_lo * hz
        qp.save()
        qp.setClipRect(QtCore.QRectF(x0, top, x1 - x0, self.SPEC_HEIGHT))
        qp.setRenderHint(QtGui.QPainter.RenderHint.SmoothPixmapTransform, True)
        qp.drawImage(QtCore.QRectF(xa, ya, xb - xa, yb - ya), img, QtCore.QRectF(k0, 0, k1 - k0, img.height()))
        qp.restore()
        if self.shown_at is None:
            self.shown_at = time.perf_counter()

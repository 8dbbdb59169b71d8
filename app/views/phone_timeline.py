"""The trajectory editor's timeline: word and phone tiers, draggable targets and boundaries, time in ms, a cursor.

Drawing and input only, after Praat's TextGrid editor: a click sets the cursor, a drag selects
a stretch of time, a boundary of the phone or word tier and a target's triangle can be
dragged. What an edit means (undo, synthesis, playback) is the editor's
(:mod:`app.views.trajectory_editor`); the arithmetic of moving a target or a boundary is
:mod:`app.models.target_editing`'s and :mod:`app.models.tier_editing`'s. Each interval is
filled with a pale tint of its label's palette colour under a strip of the colour itself;
a label that does not fit its interval is elided ("bre…", never a fragment such as "reat")
and given whole in the tooltip; the targets' lines stop short of the labels.
"""
from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from app.models.target_editing import move_target, time_ticks
from app.models.tier_editing import boundaries, move_boundary

__all__ = ["PhoneTimeline", "TimeKeys", "KEY_COMMANDS"]

#: the Praat keys the timeline and the sound under it answer while they have the focus: key -> command
KEY_COMMANDS = {
    (QtCore.Qt.Key.Key_Tab, False): "play", (QtCore.Qt.Key.Key_Backtab, False): "play-from-cursor",
    (QtCore.Qt.Key.Key_Tab, True): "play-from-cursor",
    (QtCore.Qt.Key.Key_I, True): "zoom-in", (QtCore.Qt.Key.Key_O, True): "zoom-out",
    (QtCore.Qt.Key.Key_N, True): "zoom-selection", (QtCore.Qt.Key.Key_A, True): "zoom-all",
    (QtCore.Qt.Key.Key_Escape, False): "clear-selection",
}


class TimeKeys:
    """Praat's keys for a time-axis widget (a mixin): Tab, Shift+Tab, Ctrl+I / O / N / A, Esc.

    They are taken before the window's shortcuts (Ctrl+O is File › Open elsewhere) and before
    Qt's focus chain (Tab), and sent as ``keyCommand(name)``; Space, Left / Right, Delete and
    + / - as the timeline's own signals.
    """

    def _command_of(self, ev) -> str | None:
        ctrl = bool(ev.modifiers() & QtCore.Qt.KeyboardModifier.ControlModifier)
        key = QtCore.Qt.Key(ev.key())
        if key == QtCore.Qt.Key.Key_Tab and ev.modifiers() & QtCore.Qt.KeyboardModifier.ShiftModifier:
            return "play-from-cursor"
        return KEY_COMMANDS.get((key, ctrl))

    def event(self, ev):  # noqa: D401 - Qt override
        t = ev.type()
        if t == QtCore.QEvent.Type.ShortcutOverride and (self._command_of(ev) or ev.key() == QtCore.Qt.Key.Key_Space):
            ev.accept()
            return True
        if t == QtCore.QEvent.Type.KeyPress and self._command_of(ev) is not None:
            self.keyCommand.emit(self._command_of(ev))
            ev.accept()
            return True
        return super().event(ev)


def _tint(rgb, amount: float) -> QtGui.QColor:
    """``rgb`` moved ``amount`` of the way to white."""
    r, g, b = (float(c) + amount * (1.0 - float(c)) for c in rgb)
    return QtGui.QColor.fromRgbF(r, g, b)


class PhoneTimeline(TimeKeys, QtWidgets.QWidget):
    """Word and phone intervals as boxes, targets as draggable triangles, ms ticks, a cursor and a selection.

    .. rubric:: Signals

    targetsChanged(before, after)
        A drag ended with a target on another frame (both TargetSequences).
    tiersChanged(before, after, words_before, words_after, text)
        A boundary drag ended elsewhere (targets with the phones, and the word tiers).
    selectionChanged(index or None)
        The chosen target (clicked) changed.
    pressed(frame, x), dragged(frame, x), released(frame, x)
        The mouse on the time axis (not on a target or boundary): a click or a drag over time.
    keyCommand(name)
        A Praat key (:data:`KEY_COMMANDS`).
    playToggled(), stepRequested(int), deleteRequested()
        Space, Left / Right, Delete / Backspace while the timeline has the focus.
    zoomRequested(factor, x)
        Wheel or + / - keys: zoom by ``factor`` keeping pixel ``x`` in place.
    """

    targetsChanged = QtCore.Signal(object, object)
    tiersChanged = QtCore.Signal(object, object, object, object, str)
    selectionChanged = QtCore.Signal(object)
    pressed = QtCore.Signal(float, float)
    dragged = QtCore.Signal(float, float)
    released = QtCore.Signal(float, float)
    keyCommand = QtCore.Signal(str)
    playToggled = QtCore.Signal()
    stepRequested = QtCore.Signal(int)
    deleteRequested = QtCore.Signal()
    zoomRequested = QtCore.Signal(float, float)
    MARGIN = 8
    GRAB = 6
    WORD_H, PHONE_H, TARGET_H, AXIS_H = 22, 30, 24, 18
    #: height without a word tier (the editor sizes the strip from :meth:`tiers_height`)
    HEIGHT = 2 + PHONE_H + TARGET_H + AXIS_H + 2
    #: the rows' heights on a small screen (:meth:`set_compact`)
    COMPACT = (18, 24, 20, 16)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.targets = None
        self.words = ()
        self.cursor = None
        self.selected = None
        self.time_selection = None  # (first, last) frame of the selected stretch, or None
        self.colour = None  # callable (kind, label) -> (r, g, b), the session palette's
        self._drag = None
        self._drag_start = None
        self._bdrag = None  # (tier, boundary, targets before, words before) while a boundary is dragged
        self._pressing = False
        self.setMinimumHeight(self.HEIGHT)
        self.setMouseTracking(True)
        self.setFocusPolicy(QtCore.Qt.FocusPolicy.StrongFocus)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Fixed, QtWidgets.QSizePolicy.Policy.Fixed)

    # ------------------------------------------------------------------ data
    def set_targets(self, targets, words=None) -> None:
        self.targets = targets
        if words is not None:
            self.words = tuple(words)
        self._drag = self._bdrag = None
        if self.selected is not None and (targets is None or self.selected >= len(targets.targets)):
            self.select(None)
        self.update()

    def set_compact(self, on: bool) -> None:
        """Lower rows (a laptop's screen) or the full ones."""
        self.WORD_H, self.PHONE_H, self.TARGET_H, self.AXIS_H = self.COMPACT if on else (
            PhoneTimeline.WORD_H, PhoneTimeline.PHONE_H, PhoneTimeline.TARGET_H, PhoneTimeline.AXIS_H)
        self.HEIGHT = 2 + self.PHONE_H + self.TARGET_H + self.AXIS_H + 2
        self.setMinimumHeight(self.HEIGHT)
        self.update()

    def tiers_height(self) -> int:
        """The height the tiers need: a word row only where there is a word tier."""
        return self.HEIGHT + (self.WORD_H if self.words else 0)

    def set_cursor(self, frame) -> None:
        self.cursor = frame
        self.update()

    def set_time_selection(self, span) -> None:
        self.time_selection = None if span is None else (min(span), max(span))
        self.update()

    def select(self, index) -> None:
        if index != self.selected:
            self.selected = index
            self.selectionChanged.emit(index)
        self.update()

    # ------------------------------------------------------------------ geometry
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
        return self._rows()["targets"][0] + self.TARGET_H / 2

    def _rows(self) -> dict:
        """``{row: (top, height)}`` of the word, phone, target and axis rows."""
        y, out = 2, {}
        if self.words:
            out["words"] = (y, self.WORD_H)
            y += self.WORD_H
        out["phones"] = (y, self.PHONE_H)
        y += self.PHONE_H
        out["targets"] = (y, self.TARGET_H)
        out["axis"] = (y + self.TARGET_H, self.AXIS_H)
        return out

    def interval_rect(self, tier: str, index: int) -> QtCore.QRectF:
        """Where interval ``index`` of ``tier`` ("phones" or "words") is drawn."""
        iv = (self.targets.phones if tier == "phones" else self.words)[index]
        top, h = self._rows()[tier]
        r = self.targets.rate
        x0, x1 = self._x(iv.start * r), self._x(iv.end * r)
        return QtCore.QRectF(x0, top, max(x1 - x0, 1.0), h)

    def label_shown(self, tier: str, index: int) -> str:
        """The text drawn in interval ``index`` of ``tier``: the label, elided to fit ("" when not even one letter
        fits)."""
        iv = (self.targets.phones if tier == "phones" else self.words)[index]
        width = self.interval_rect(tier, index).width() - 4
        fm = self.fontMetrics()
        if fm.horizontalAdvance(iv.label) <= width:
            return iv.label
        shown = fm.elidedText(iv.label, QtCore.Qt.TextElideMode.ElideRight, int(width))
        return shown if len(shown) > 1 else ""

    def ticks(self) -> tuple[int, list[int]]:
        """(step, tick times) of the time axis in ms, for the current width."""
        t = self.targets
        if t is None:
            return 0, []
        return time_ticks(0.0, 1000.0 * (t.n_frames - 1) / t.rate, self.width() - 2 * self.MARGIN)

    # ------------------------------------------------------------------ painting
    def paintEvent(self, _event):
        qp = QtGui.QPainter(self)
        qp.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing)
        qp.fillRect(self.rect(), QtGui.QColor("white"))
        if self.targets is None:
            qp.setPen(QtGui.QColor("gray"))
            qp.drawText(self.rect(), QtCore.Qt.AlignmentFlag.AlignCenter, "no targets: choose an input and press Load")
            return
        t, rows = self.targets, self._rows()
        tiers = [("words", self.words)] if self.words else []
        tiers.append(("phones", t.phones))
        for tier, ivs in tiers:  # boxes
            for i, iv in enumerate(ivs):
                rect = self.interval_rect(tier, i)
                rgb = self.colour(tier[:-1], iv.label) if self.colour is not None and iv.label else (0.8, 0.8, 0.85)
                qp.fillRect(rect, _tint(rgb, 0.78))
                qp.fillRect(QtCore.QRectF(rect.left(), rect.top(), rect.width(), 3), _tint(rgb, 0.0))
            qp.setPen(QtGui.QPen(QtGui.QColor("#556"), 1))
            for _k, bt in boundaries(ivs):
                x = self._x(bt * t.rate)
                qp.drawLine(QtCore.QPointF(x, rows[tier][0]), QtCore.QPointF(x, rows[tier][0] + rows[tier][1]))
        if self.time_selection is not None:  # the selected stretch, across the tiers
            a, b = self.time_selection
            top = rows["words" if self.words else "phones"][0]
            qp.fillRect(QtCore.QRectF(self._x(a), top, max(self._x(b) - self._x(a), 1.0),
                                      rows["axis"][0] - top), QtGui.QColor(255, 150, 170, 70))
        ym = self.marker_y()
        for i, tg in enumerate(t.targets):  # target stems: behind the labels, drawn next
            x = self._x(tg.frame)
            col = QtGui.QColor("#ff7f00" if i == self._drag else "#1f5fbf" if i == self.selected else "#c00000")
            qp.setPen(QtGui.QPen(col, 1, QtCore.Qt.PenStyle.DashLine))
            qp.drawLine(QtCore.QPointF(x, rows["phones"][0]), QtCore.QPointF(x, ym - 6))
        for tier, ivs in tiers:  # labels on a background of their box: never struck through
            fm = self.fontMetrics()
            for i, iv in enumerate(ivs):
                text = self.label_shown(tier, i)
                if not text:
                    continue
                rect = self.interval_rect(tier, i)
                w = fm.horizontalAdvance(text) + 4
                back = QtCore.QRectF(rect.center().x() - w / 2, rect.top() + 4, w, rect.height() - 5)
                rgb = self.colour(tier[:-1], iv.label) if self.colour is not None and iv.label else (0.8, 0.8, 0.85)
                qp.fillRect(back, _tint(rgb, 0.78))
                qp.setPen(QtGui.QColor("#222"))
                qp.drawText(back, QtCore.Qt.AlignmentFlag.AlignCenter, text)
        for i, tg in enumerate(t.targets):  # triangles
            x = self._x(tg.frame)
            col = QtGui.QColor("#ff7f00" if i == self._drag else "#1f5fbf" if i == self.selected else "#c00000")
            qp.setPen(QtCore.Qt.PenStyle.NoPen)
            qp.setBrush(col)
            qp.drawPolygon(QtGui.QPolygonF([QtCore.QPointF(x, ym - 6), QtCore.QPointF(x - 6, ym + 6),
                                            QtCore.QPointF(x + 6, ym + 6)]))
        # time axis, ticks in ms
        y_axis = rows["axis"][0] + 1
        qp.setPen(QtGui.QColor("#888"))
        qp.drawLine(QtCore.QPointF(self.MARGIN, y_axis), QtCore.QPointF(self.width() - self.MARGIN, y_axis))
        _step, ticks = self.ticks()
        font = qp.font()
        font.setPointSizeF(max(font.pointSizeF() - 1.5, 6.0))
        qp.setFont(font)
        for ms in ticks:
            x = self._x(ms / 1000.0 * t.rate)
            qp.drawLine(QtCore.QPointF(x, y_axis), QtCore.QPointF(x, y_axis + 4))
            rect = QtCore.QRectF(x - 40, y_axis + 3, 80, 14)  # centred on its tick, never cut at an edge
            align = QtCore.Qt.AlignmentFlag.AlignHCenter
            if rect.left() < 0:
                rect.moveLeft(0.0)
                align = QtCore.Qt.AlignmentFlag.AlignLeft
            elif rect.right() > self.width():
                rect.moveRight(float(self.width()))
                align = QtCore.Qt.AlignmentFlag.AlignRight
            qp.drawText(rect, align, f"{ms} ms" if ms == ticks[-1] or ms == 0 else f"{ms}")
        if self.cursor is not None:
            qp.setPen(QtGui.QPen(QtGui.QColor("black"), 2))
            x = self._x(self.cursor)
            qp.drawLine(QtCore.QPointF(x, 0), QtCore.QPointF(x, self.height()))
        qp.end()

    # ------------------------------------------------------------------ hit tests
    def _hit(self, pos) -> int | None:
        """The target whose triangle is under ``pos``, or None."""
        if self.targets is None or abs(pos.y() - self.marker_y()) > 12:
            return None
        xs = np.array([self._x(tg.frame) for tg in self.targets.targets])
        if xs.size == 0:
            return None
        i = int(np.argmin(np.abs(xs - pos.x())))
        return i if abs(xs[i] - pos.x()) <= self.GRAB + 1 else None

    def boundary_at(self, pos) -> tuple[str, int] | None:
        """``(tier, boundary)`` of the tier boundary under ``pos`` (within a few pixels), or None."""
        if self.targets is None:
            return None
        for tier, ivs in (("words", self.words), ("phones", self.targets.phones)):
            row = self._rows().get(tier)
            if row is None or not row[0] <= pos.y() <= row[0] + row[1]:
                continue
            found = [(abs(self._x(bt * self.targets.rate) - pos.x()), k) for k, bt in boundaries(ivs)]
            if found and min(found)[0] <= self.GRAB:
                return tier, min(found)[1]
        return None

    def boundary_x(self, tier: str, k: int) -> float:
        """Pixel x of boundary ``k`` of ``tier`` (for tests and tools)."""
        ivs = self.targets.phones if tier == "phones" else self.words
        return self._x(float(ivs[k].start) * self.targets.rate)

    def interval_at(self, pos):
        """``(tier, index)`` of the interval under ``pos``, or None."""
        if self.targets is None:
            return None
        for tier, ivs in (("words", self.words), ("phones", self.targets.phones)):
            row = self._rows().get(tier)
            if row is not None and row[0] <= pos.y() <= row[0] + row[1]:
                for i in range(len(ivs)):
                    if self.interval_rect(tier, i).contains(pos):
                        return tier, i
        return None

    # ------------------------------------------------------------------ input
    def event(self, ev):
        if ev.type() == QtCore.QEvent.Type.ToolTip and self.targets is not None:
            QtWidgets.QToolTip.showText(ev.globalPos(), self._tooltip(ev.pos()) or "", self)
            return True
        return super().event(ev)

    def _tooltip(self, pos) -> str:
        t = self.targets
        i = self._hit(QtCore.QPointF(pos))
        if i is not None:
            tg = t.targets[i]
            state = "" if tg.state is None else f", state {tg.state}"
            return f"target {i + 1}: {tg.label or 'clicked state'} at {1000 * tg.frame / t.rate:.0f} ms{state}"
        hit = self.interval_at(QtCore.QPointF(pos))
        if hit is None:
            return ""
        iv = (t.phones if hit[0] == "phones" else self.words)[hit[1]]
        return f"{hit[0][:-1]} {iv.label!r}: {1000 * iv.start:.0f}–{1000 * iv.end:.0f} ms"

    def mousePressEvent(self, ev):
        self.setFocus(QtCore.Qt.FocusReason.MouseFocusReason)
        pos = ev.position()
        self._drag = self._hit(pos)
        self._drag_start = self.targets
        if self._drag is not None:
            self.select(self._drag)
        elif (b := self.boundary_at(pos)) is not None:
            self._bdrag = (b[0], b[1], self.targets, self.words)
        elif self.targets is not None and ev.button() == QtCore.Qt.MouseButton.LeftButton:
            self._pressing = True
            self.pressed.emit(self.frame_at(pos.x()), pos.x())
        self.update()

    def mouseMoveEvent(self, ev):
        pos = ev.position()
        if self._drag is not None:
            self.targets = move_target(self.targets, self._drag, int(round(self.frame_at(pos.x()))))
            self.update()
        elif self._bdrag is not None:
            tier, k, t0, w0 = self._bdrag
            self.targets, self.words = move_boundary(t0, w0, tier, k, self.frame_at(pos.x()) / t0.rate)
            self.update()
        elif self._pressing:
            self.dragged.emit(self.frame_at(pos.x()), pos.x())
        else:
            over = self._hit(pos) is not None or self.boundary_at(pos) is not None
            self.setCursor(QtCore.Qt.CursorShape.SizeHorCursor if over else QtCore.Qt.CursorShape.ArrowCursor)

    def mouseReleaseEvent(self, ev):
        if self._drag is not None:
            i, self._drag = self._drag, None
            self.update()
            before = self._drag_start
            if before is not None and before.targets[i].frame != self.targets.targets[i].frame:
                self.targetsChanged.emit(before, self.targets)
        elif self._bdrag is not None:
            tier, k, t0, w0 = self._bdrag
            self._bdrag = None
            if t0.phones != self.targets.phones or tuple(w0) != tuple(self.words):
                self.tiersChanged.emit(t0, self.targets, tuple(w0), tuple(self.words),
                                       f"move {tier[:-1]} boundary {k}")
        elif self._pressing:
            self._pressing = False
            self.released.emit(self.frame_at(ev.position().x()), ev.position().x())

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

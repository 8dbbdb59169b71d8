"""The gestural landmarks of one utterance as a point tier of the editor's time strip, draggable.

Drawing and input only (what an edit does, undo and the views that follow, is the editor's,
:mod:`app.views.editor.signals_control`). Each gesture's span (GONS to GOFFS) is a pale band,
its nucleus (NONS to NOFFS) a darker one; each landmark a line in its palette colour with its
name where there is room (the whole description in the tooltip). A press on a landmark chooses
it and a drag moves it, held between its gesture's neighbouring landmarks
(:meth:`app.models.gesture_editing.GestureEditor.bounds`) while it moves; Delete marks the
chosen landmark missing; the context menu also removes a whole gesture (a false detection).
A press elsewhere is time input, as on the tiers.
"""
from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

from app.models.signals import LANDMARK_WORDS, landmark_colour
from app.views.strip_row import StripRow
from engine.recordings.signals.gestures import LANDMARKS

__all__ = ["GestureTier"]


class GestureTier(StripRow):
    """The landmarks of one utterance's gestures (module docstring).

    .. rubric:: Signals

    landmarkMoved(gesture, landmark, time_s)
        A drag ended with the landmark at another time.
    clearRequested(gesture, landmark), removeRequested(gesture)
        Delete on the chosen landmark; the context menu's entries.
    chosenChanged(object)
        The chosen ``(gesture, landmark)`` or None.
    """

    landmarkMoved = QtCore.Signal(int, int, float)
    clearRequested = QtCore.Signal(int, int)
    removeRequested = QtCore.Signal(int)
    chosenChanged = QtCore.Signal(object)
    #: its height, and on a small screen (:meth:`set_compact`)
    HEIGHT, COMPACT_HEIGHT = 26, 20
    GRAB = 5

    def __init__(self, parent=None):
        super().__init__(parent)
        self.editor = None  # app.models.gesture_editing.GestureEditor
        self.utterance = None
        self.palette = None
        self.message = ""
        self.chosen = None  # (gesture, landmark)
        self._drag = None  # (gesture, landmark, lo, hi) while a landmark is dragged
        self._preview = None  # the dragged landmark's time now
        self.setFixedHeight(self.HEIGHT)

    def set_compact(self, on: bool) -> None:
        self.setFixedHeight(self.COMPACT_HEIGHT if on else self.HEIGHT)
        self.update()

    def set_gestures(self, editor, utterance, palette, message: str = "") -> None:
        """Show ``editor``'s landmarks of ``utterance`` (None: ``message`` instead)."""
        self.editor, self.utterance, self.palette, self.message = editor, utterance, palette, message
        if self.chosen is not None and (editor is None or self.chosen[0] >= len(editor.gestures)):
            self.choose(None)
        self._drag = self._preview = None
        self.update()

    def choose(self, which) -> None:
        if which != self.chosen:
            self.chosen = which
            self.chosenChanged.emit(which)
        self.update()

    # ------------------------------------------------------------------ reading
    def points(self) -> list:
        """``[(t, name, gesture, landmark)]`` drawn now (the dragged landmark at its preview time)."""
        if self.editor is None or self.utterance is None:
            return []
        pts = self.editor.points(self.utterance)
        if self._drag is not None:
            g, j = self._drag[:2]
            pts = [(self._preview if (gg, jj) == (g, j) else t, n, gg, jj) for t, n, gg, jj in pts]
        return pts

    def point_x(self, gesture: int, landmark: int) -> float:
        """Pixel x of a landmark (for tests and tools)."""
        return self.time_x(float(self.editor.gestures.times[gesture, landmark]))

    def landmark_at(self, x: float):
        """``(gesture, landmark)`` within a few pixels of ``x``, or None."""
        if self.editor is None or self.utterance is None:
            return None
        px_per_s = max(self.time_x(1.0) - self.time_x(0.0), 1e-9)
        return self.editor.nearest(self.utterance, self.x_time(x), tolerance_s=self.GRAB / px_per_s)

    def _colour(self, name):
        rgb = landmark_colour(self.palette, name) if self.palette is not None else (0.3, 0.3, 0.3)
        return QtGui.QColor.fromRgbF(*rgb)

    # ------------------------------------------------------------------ painting
    def paint_content(self, qp) -> None:
        h = self.height()
        if self.editor is None or self.utterance is None:
            if self.message:
                self.small_font(qp)
                qp.setPen(QtGui.QColor("gray"))
                qp.drawText(self.rect(), QtCore.Qt.AlignmentFlag.AlignCenter, self.message)
            return
        gs = self.editor.gestures
        pts = self.points()
        times = {(g, j): t for t, _n, g, j in pts}
        for g in gs.of_utterance(self.utterance).tolist():  # spans, then nuclei
            for (a, b), shade in (((0, 6), QtGui.QColor(90, 110, 150, 28)), ((2, 4), QtGui.QColor(90, 110, 150, 60))):
                ta, tb = times.get((g, a)), times.get((g, b))
                if ta is not None and tb is not None and tb > ta:
                    qp.fillRect(QtCore.QRectF(self.time_x(ta), 2, self.time_x(tb) - self.time_x(ta), h - 4), shade)
        self.small_font(qp, 2.0)
        fm = qp.fontMetrics()
        pts = sorted(pts, key=lambda p: p[0])
        xs = [self.time_x(t) for t, *_ in pts]
        for x, (_t, name, g, j) in zip(xs, pts):  # the lines, then the names over them
            chosen = (g, j) == self.chosen
            qp.setPen(QtGui.QPen(QtGui.QColor("#111") if chosen else self._colour(name), 3 if chosen else 2))
            qp.drawLine(QtCore.QPointF(x, 1), QtCore.QPointF(x, h - 1))
        right = -1e9
        for k, (x, (_t, name, _g, _j)) in enumerate(zip(xs, pts)):
            w = fm.horizontalAdvance(name) + 2
            nxt = xs[k + 1] if k + 1 < len(xs) else self.width()
            if x + 3 > right and x + 3 + w < nxt:  # a name only where it fits before the next line
                box = QtCore.QRectF(x + 2, (h - fm.height()) / 2, w, fm.height())
                qp.fillRect(box, QtGui.QColor(255, 255, 255, 200))
                qp.setPen(QtGui.QColor("#222"))
                qp.drawText(box, QtCore.Qt.AlignmentFlag.AlignCenter, name)
                right = x + 3 + w

    # ------------------------------------------------------------------ input
    def press_content(self, ev) -> bool:
        hit = self.landmark_at(ev.position().x())
        if hit is None:
            if ev.button() == QtCore.Qt.MouseButton.LeftButton:
                self.choose(None)
            return ev.button() != QtCore.Qt.MouseButton.LeftButton
        self.choose(hit)
        if ev.button() == QtCore.Qt.MouseButton.LeftButton:
            lo, hi = self.editor.bounds(*hit)
            self._drag = (hit[0], hit[1], lo, hi)
            self._preview = float(self.editor.gestures.times[hit])
        return True

    def mouseMoveEvent(self, ev):
        if self._drag is not None:
            g, j, lo, hi = self._drag
            self._preview = min(max(self.x_time(ev.position().x()), lo), hi)
            self.update()
            return
        if not self._pressing:
            over = self.landmark_at(ev.position().x()) is not None
            self.setCursor(QtCore.Qt.CursorShape.SizeHorCursor if over else QtCore.Qt.CursorShape.ArrowCursor)
        super().mouseMoveEvent(ev)

    def mouseReleaseEvent(self, ev):
        if self._drag is not None:
            g, j, _lo, _hi = self._drag
            t = self._preview
            self._drag = self._preview = None
            self.update()
            if abs(t - float(self.editor.gestures.times[g, j])) > 1e-9:
                self.landmarkMoved.emit(g, j, t)
            return
        super().mouseReleaseEvent(ev)

    def keyPressEvent(self, ev):
        if ev.key() in (QtCore.Qt.Key.Key_Delete, QtCore.Qt.Key.Key_Backspace) and self.chosen is not None:
            self.clearRequested.emit(*self.chosen)
            ev.accept()
            return
        super().keyPressEvent(ev)

    def contextMenuEvent(self, ev):
        hit = self.landmark_at(ev.pos().x())
        if hit is None:
            return
        g, j = hit
        number = self._number(g)
        menu = QtWidgets.QMenu(self)
        name = LANDMARKS[j]
        menu.addAction(f"Mark {name} of gesture {number} missing (Delete)",
                       lambda: self.clearRequested.emit(g, j))
        menu.addAction(f"Remove gesture {number} (a false detection)", lambda: self.removeRequested.emit(g))
        menu.popup(ev.globalPos())
        self._menu = menu

    def _number(self, g: int) -> int:
        """Gesture ``g``'s number within its utterance (1-based, as the gesture table counts)."""
        own = self.editor.gestures.of_utterance(self.utterance).tolist()
        return own.index(g) + 1 if g in own else g + 1

    def tooltip_text(self, x: float) -> str:
        hit = self.landmark_at(x)
        if hit is None:
            return self.message or "gestural landmarks: drag one to move it; Delete marks the chosen one missing"
        g, j = hit
        gs = self.editor.gestures
        name = LANDMARKS[j]
        text = (f"gesture {self._number(g)} of {gs.track}: {name} ({LANDMARK_WORDS[name]}) at "
                f"{1000 * gs.times[g, j]:.1f} ms")
        if name in ("PVEL", "PVEL2"):
            text += f"; peak speed {gs.peak_velocity[g, 0 if name == 'PVEL' else 1]:.3g} {gs.unit}/s"
        if name == "MAXC":
            text += f"; {gs.track} {gs.maxc_value[g]:.3g} {gs.unit}"
        return text

    def event(self, ev):
        if ev.type() == QtCore.QEvent.Type.ToolTip:
            QtWidgets.QToolTip.showText(ev.globalPos(), self.tooltip_text(ev.pos().x()), self)
            return True
        return super().event(ev)

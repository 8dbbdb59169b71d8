"""Trajectory editor: a phone timeline with draggable targets, a method chooser, Synthesise and Play.

Targets come from a corpus utterance (its phone mid-points, with their oracle
states: the paper's Fig. 3 experiment), typed English text, a phone string with
durations (``p 0.08 ax 0.05 ...``) or a TextGrid / .lab file, and from clicked
states: "Add clicked state" (Ctrl+T) inserts a target holding the selected state at
the playback cursor, or after the last target. Dragging a target marker moves its frame. The synthetic trajectory is drawn red in the manifold view
and played beside the original in the lip view; for an utterance the error
against the captured original is shown.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from app.state import TrajectoryData
from app.views._common import connect_all, disconnect_all, Throttle

__all__ = ["TrajectoryEditor", "PhoneTimeline", "synthesize_targets", "trajectory_error", "move_target"]

SOURCES = (("utterance", "Utterance"), ("text", "Text"), ("phones", "Phones + durations"), ("textgrid", "TextGrid"))
ADD_STATE_SHORTCUT = "Ctrl+T"
METHOD_LABELS = {"manifold": "Manifold (max-probability path)", "linear": "Linear interpolation (X)",
                 "cubic": "Cubic spline (X)", "unitselection": "Unit selection"}


# ============================================================================ pure helpers
def move_target(targets, index: int, frame: int):
    """A copy of ``targets`` with target ``index`` moved to ``frame``, clamped between its neighbours."""
    ts = list(targets.targets)
    lo = ts[index - 1].frame + 1 if index > 0 else 0
    hi = ts[index + 1].frame - 1 if index + 1 < len(ts) else targets.n_frames - 1
    f = int(np.clip(int(frame), lo, max(lo, hi)))
    ts[index] = replace(ts[index], frame=f)
    return replace(targets, targets=tuple(ts))


def synthesize_targets(manifold, targets, method: str, synthesizers: dict | None = None):
    """Run synthesis method ``method`` on ``targets``; returns (TrajectoryData, engine Trajectory).

    The manifold method runs with ``strict=False`` so a target that cannot be reached
    in time is undershot (and said so in the trajectory's warnings) instead of failing.
    ``synthesizers`` caches fitted synthesisers per method.
    """
    from engine.synthesis import make_synthesizer

    cache = synthesizers if synthesizers is not None else {}
    if method not in cache:
        params = {"strict": False} if method == "manifold" else {}
        cache[method] = make_synthesizer(method, manifold, **params)
    traj = cache[method].synthesize(targets)
    Y = traj.Fy
    if Y is None:  # methods that move in X: place them in Y out of sample
        Y = manifold.project(traj.frames(manifold))
    data = TrajectoryData(Y=np.asarray(Y, np.float32), Fx=np.asarray(traj.Fx, np.float32), frames=None,
                          label=METHOD_LABELS.get(method, method).split(" (")[0], rate=float(targets.rate),
                          extra={"method": method, "warnings": list(traj.warnings),
                                 "target_frames": np.asarray(traj.target_frames)})
    return data, traj


def trajectory_error(manifold, synthetic, original) -> dict:
    """Error of a synthetic trajectory against the captured original, as ``lipspace evaluate`` scores it.

    The first ``n = min(len(synthetic), len(original))`` frames are compared through
    :func:`engine.evaluation.trajectory_errors`, so the editor's readout and the
    evaluation table are the same numbers. Returns its dict: ``rmse_x`` (root mean
    square over frames of the Euclidean error in X), ``mean_point_error`` and
    ``max_point_error`` (per-point Euclidean error in the corpus's units), ``frames``.
    """
    from engine.evaluation import trajectory_errors

    n = min(len(synthetic), len(original))
    frames = manifold.corpus_.frames[np.asarray(original.frames[:n])]
    return trajectory_errors(manifold, np.asarray(synthetic.Fx[:n]), frames)


# ============================================================================ timeline widget
class PhoneTimeline(QtWidgets.QWidget):
    """Phone intervals as boxes, targets as draggable triangles, the playback position as a line.

    Signals ``targetsChanged(object)`` with the new TargetSequence after a drag.
    """

    targetsChanged = QtCore.Signal(object)
    MARGIN = 8
    GRAB = 7

    def __init__(self, parent=None):
        super().__init__(parent)
        self.targets = None
        self.cursor = None
        self._drag = None
        self.setMinimumHeight(74)
        self.setMouseTracking(True)
        self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding, QtWidgets.QSizePolicy.Policy.Fixed)

    def set_targets(self, targets) -> None:
        self.targets = targets
        self._drag = None
        self.update()

    def set_cursor(self, frame) -> None:
        self.cursor = frame
        self.update()

    # geometry
    def _x(self, frame: float) -> float:
        n = max(self.targets.n_frames - 1, 1)
        return self.MARGIN + (self.width() - 2 * self.MARGIN) * frame / n

    def _frame(self, x: float) -> int:
        n = max(self.targets.n_frames - 1, 1)
        return int(round((x - self.MARGIN) / max(self.width() - 2 * self.MARGIN, 1) * n))

    def marker_x(self, index: int) -> float:
        """Pixel x of target ``index`` (for tests and tools)."""
        return self._x(self.targets.targets[index].frame)

    def marker_y(self) -> float:
        return self.height() - 14

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
        top, box_h = 4, h - 34
        for i, p in enumerate(t.phones):
            x0, x1 = self._x(p.start * t.rate), self._x(p.end * t.rate)
            qp.fillRect(QtCore.QRectF(x0, top, max(x1 - x0, 1), box_h),
                        QtGui.QColor("#e8e8f0" if i % 2 else "#d4d8e8"))
            qp.setPen(QtGui.QColor("#222"))
            qp.drawText(QtCore.QRectF(x0, top, max(x1 - x0, 1), box_h), QtCore.Qt.AlignmentFlag.AlignCenter, p.label)
        # time axis
        qp.setPen(QtGui.QColor("#888"))
        y_axis = top + box_h + 2
        qp.drawLine(QtCore.QPointF(self.MARGIN, y_axis), QtCore.QPointF(self.width() - self.MARGIN, y_axis))
        # targets
        ym = self.marker_y()
        for i, tg in enumerate(t.targets):
            x = self._x(tg.frame)
            col = QtGui.QColor("#c00000" if self._drag != i else "#ff7f00")
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

    def _hit(self, pos) -> int | None:
        if self.targets is None or abs(pos.y() - self.marker_y()) > 12:
            return None
        xs = np.array([self._x(tg.frame) for tg in self.targets.targets])
        if xs.size == 0:
            return None
        i = int(np.argmin(np.abs(xs - pos.x())))
        return i if abs(xs[i] - pos.x()) <= self.GRAB else None

    def mousePressEvent(self, ev):
        self._drag = self._hit(ev.position())
        self.update()

    def mouseMoveEvent(self, ev):
        if self._drag is None:
            self.setCursor(QtCore.Qt.CursorShape.SizeHorCursor if self._hit(ev.position()) is not None
                           else QtCore.Qt.CursorShape.ArrowCursor)
            return
        self.targets = move_target(self.targets, self._drag, self._frame(ev.position().x()))
        self.update()

    def mouseReleaseEvent(self, ev):
        if self._drag is not None:
            self._drag = None
            self.update()
            self.targetsChanged.emit(self.targets)


# ============================================================================ the editor
class TrajectoryEditor(QtWidgets.QWidget):
    """Build targets, synthesise, play and compare; bound to an :class:`app.state.AppState`."""

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.state = state
        self.targets = None
        self.synthesizers: dict = {}
        self._runner = None
        self.last_error = None

        self.source_box = QtWidgets.QComboBox()
        for key, label in SOURCES:
            self.source_box.addItem(label, key)
        self.utt_box = QtWidgets.QComboBox()
        self.utt_box.setMinimumContentsLength(10)
        self.text_edit = QtWidgets.QLineEdit()
        self.text_edit.setPlaceholderText("type English text, e.g. 'Herb's birthday'")
        self.browse_btn = QtWidgets.QPushButton("Open…")
        self.oracle_box = QtWidgets.QCheckBox("Oracle states")
        self.oracle_box.setChecked(True)
        self.oracle_box.setToolTip("Targets carry the utterance's own states at the phone mid-points (paper Fig. 3);"
                                   " untick to synthesise from the phone labels and times only")
        self.load_btn = QtWidgets.QPushButton("Load")
        self.add_state_btn = QtWidgets.QPushButton("Add clicked state")
        self.add_state_btn.setShortcut(QtGui.QKeySequence(ADD_STATE_SHORTCUT))
        self.add_state_btn.setToolTip(f"Insert a target holding the state selected in the manifold view at the "
                                      f"playback cursor, or after the last target ({ADD_STATE_SHORTCUT})")
        self.add_state_btn.setEnabled(False)
        self.method_box = QtWidgets.QComboBox()
        self.synth_btn = QtWidgets.QPushButton("Synthesise")
        self.play_btn = QtWidgets.QPushButton("Play")
        self.readout = QtWidgets.QLabel("")
        self.readout.setTextInteractionFlags(QtCore.Qt.TextInteractionFlag.TextSelectableByMouse)
        self.readout.setWordWrap(True)
        self.timeline = PhoneTimeline()

        row1 = QtWidgets.QHBoxLayout()
        for w in (QtWidgets.QLabel("Input:"), self.source_box, self.utt_box, self.text_edit, self.browse_btn,
                  self.oracle_box, self.load_btn, self.add_state_btn):
            row1.addWidget(w)
        row1.setStretchFactor(self.text_edit, 1)
        row1.addStretch(0)
        row2 = QtWidgets.QHBoxLayout()
        for w in (QtWidgets.QLabel("Method:"), self.method_box, self.synth_btn, self.play_btn):
            row2.addWidget(w)
        row2.addWidget(self.readout, 1)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addLayout(row1)
        lay.addWidget(self.timeline)
        lay.addLayout(row2)

        self.source_box.currentIndexChanged.connect(lambda _i: self._sync_inputs())
        self.utt_box.activated.connect(lambda _i: self.load())
        self.text_edit.returnPressed.connect(self.load)
        self.browse_btn.clicked.connect(self._browse)
        self.load_btn.clicked.connect(self.load)
        self.add_state_btn.clicked.connect(self.add_selected_state)
        self.oracle_box.toggled.connect(lambda _on: self.load() if self.source == "utterance" else None)
        self.synth_btn.clicked.connect(self.synthesize)
        self.play_btn.clicked.connect(lambda: self.state.set_playing(True))
        self.timeline.targetsChanged.connect(self._on_dragged)
        ev = state.events
        # the cursor follows playback a few times a second (each repaint composes the whole window)
        self._cursor_readout = Throttle(self.timeline.set_cursor, 0.2, parent=self)
        self._connections = [(ev.manifold, lambda _m: self.rebuild()), (ev.playback, self._cursor_readout),
                             (ev.utterance, self._on_utterance),
                             (ev.state, lambda st: self.add_state_btn.setEnabled(st is not None))]
        connect_all(self._connections)
        self.rebuild()  # fills the methods once a manifold is there

    # ------------------------------------------------------------------ setup
    def _fill_methods(self):
        try:
            from engine.synthesis import METHODS
        except ImportError as exc:  # synthesis unavailable: say so, keep the rest working
            METHODS = ()
            self.readout.setText(f"synthesis unavailable: {exc}")
        for m in METHODS:
            self.method_box.addItem(METHOD_LABELS.get(m, m), m)

    @property
    def source(self) -> str:
        return self.source_box.currentData()

    @property
    def method(self) -> str:
        return self.method_box.currentData()

    def set_method(self, method: str) -> None:
        i = self.method_box.findData(method)
        if i < 0:
            raise ValueError(f"unknown synthesis method {method!r}")
        self.method_box.setCurrentIndex(i)

    def set_source(self, source: str) -> None:
        i = self.source_box.findData(source)
        if i < 0:
            raise ValueError(f"unknown input {source!r}; choose from {[k for k, _ in SOURCES]}")
        self.source_box.setCurrentIndex(i)

    def _sync_inputs(self):
        s = self.source
        self.utt_box.setVisible(s == "utterance")
        self.oracle_box.setVisible(s == "utterance")
        self.text_edit.setVisible(s in ("text", "phones", "textgrid"))
        self.browse_btn.setVisible(s == "textgrid")
        self.text_edit.setPlaceholderText({"text": "type English text, e.g. 'Herb's birthday'",
                                           "phones": "label duration pairs, e.g. 'p 0.08 ax 0.05 m 0.07'",
                                           "textgrid": "path of a TextGrid or .lab file"}.get(s, ""))

    def rebuild(self) -> None:
        m = self.state.manifold
        if m is not None and self.method_box.count() == 0:
            # engine.synthesis pulls in scikit-learn (seconds at start-up); by the time a manifold
            # is loaded it is imported already, so the empty window opens without it
            self._fill_methods()
        self.synthesizers = {}
        self.targets = None
        self.timeline.set_targets(None)
        self.utt_box.blockSignals(True)
        self.utt_box.clear()
        if m is not None:
            for u in m.corpus_.utterances:
                self.utt_box.addItem(f"{u.id}" + (f" — {u.text[:40]}" if u.text else ""), u.id)
        self.utt_box.blockSignals(False)
        self.add_state_btn.setEnabled(m is not None and self.state.state is not None)
        self._sync_inputs()

    def _on_utterance(self, uid):
        if uid is None:
            return
        i = self.utt_box.findData(uid)
        if i >= 0 and i != self.utt_box.currentIndex():
            self.utt_box.blockSignals(True)
            self.utt_box.setCurrentIndex(i)
            self.utt_box.blockSignals(False)

    def _browse(self):
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self, "Open alignment", "",
                                                        "Alignments (*.TextGrid *.textgrid *.lab);;All files (*)")
        if path:
            self.text_edit.setText(path)
            self.load()

    # ------------------------------------------------------------------ targets
    def load(self) -> bool:
        """Build targets from the chosen input; returns False (and says why) on bad input."""
        from engine import targets as T

        m = self.state.manifold
        if m is None:
            return False
        s, text = self.source, self.text_edit.text().strip()
        try:
            if s == "utterance":
                uid = self.utt_box.currentData()
                if uid is None:
                    raise ValueError("the corpus has no utterances")
                tg = T.targets_from_utterance(m, uid, on_collision="merge")
                if not self.oracle_box.isChecked():
                    tg = tg.phones_only()
                if self.state.utterance != uid:
                    self.state.set_utterance(uid)
                else:
                    self.state.set_trajectories(synthetic=None)
            elif s == "text":
                tg = T.targets_from_text(m, text, on_collision="merge")
            elif s == "phones":
                tg = T.targets_from_phones(m, text, on_collision="merge")
            else:
                if not text:
                    raise ValueError("give the path of a TextGrid or .lab file (Open…)")
                tg = T.targets_from_textgrid(m, text, on_collision="merge")
            if s != "utterance":
                self.state.set_utterance(None)
        except (ValueError, KeyError, OSError) as exc:
            return self._show_error(exc)
        return self._set_targets(tg, f"{len(tg.targets)} targets over {tg.n_frames} frames "
                                     f"({tg.n_frames / tg.rate:.2f} s) from {tg.source}")

    def set_text(self, text: str, source: str = "text") -> bool:
        """Type ``text`` into the chosen input kind and load it (used by tests and scripts)."""
        self.set_source(source)
        self.text_edit.setText(text)
        return self.load()

    def add_selected_state(self) -> bool:
        """Insert a target holding the selected state at the playback cursor (else after the last target)."""
        cursor = self.timeline.cursor if self.targets is not None else None
        try:
            tg = self.state.selected_state_target(self.targets, frame=cursor)
        except ValueError as exc:
            return self._show_error(exc)
        return self._set_targets(tg, f"state {self.state.state} added as a target: {len(tg.targets)} targets "
                                     f"over {tg.n_frames} frames; press Synthesise")

    def _show_error(self, exc) -> bool:
        self.readout.setText(f"<span style='color:#b00'>{exc}</span>")
        return False

    def _set_targets(self, targets, message: str) -> bool:
        self.targets = targets
        self.timeline.set_targets(targets)
        self.readout.setText(message)
        return True

    def _on_dragged(self, targets):
        self.targets = targets
        self.readout.setText("targets moved: press Synthesise")

    # ------------------------------------------------------------------ synthesis
    def synthesize(self):
        """Synthesise the current targets with the chosen method in a worker thread."""
        from app.workers import run_task

        if self.targets is None and not self.load():
            return None
        m, tg, method = self.state.manifold, self.targets, self.method
        if method is None:
            self.readout.setText("no synthesis method available")
            return None
        orig = self.state.original if (self.source == "utterance" and self.state.original is not None
                                       and len(self.state.original) == tg.n_frames) else None

        def task(progress):
            progress("synthesising", 0, 1)
            data, _traj = synthesize_targets(m, tg, method, self.synthesizers)
            err = trajectory_error(m, data, orig) if orig is not None else None
            progress("synthesising", 1, 1)
            return data, err

        self.synth_btn.setEnabled(False)
        self.readout.setText(f"synthesising with {method}…")
        self._runner = run_task(task, parent=self, title="Synthesising", on_done=self._on_synth,
                                on_error=self._on_synth_error, on_cancel=lambda: self._on_synth_error("cancelled", ""))
        return self._runner

    def _on_synth(self, result):
        data, err = result
        self.synth_btn.setEnabled(True)
        self.state.set_trajectories(synthetic=data)
        text = f"{data.label}: {len(data)} frames"
        if err is not None:
            text += (f"; error vs original: RMSE(X) {err['rmse_x']:.4g}, per-point mean {err['mean_point_error']:.3g} "
                     f"/ max {err['max_point_error']:.3g} (corpus units)")
        warns = data.extra.get("warnings") or []
        if warns:
            text += f"; {len(warns)} warning(s): {warns[0]}"
        self.last_error = err
        self.readout.setText(text)

    def _on_synth_error(self, message, _tb=""):
        self.synth_btn.setEnabled(True)
        self.readout.setText(f"<span style='color:#b00'>synthesis failed: {message}</span>")

    def settings(self) -> dict:
        """Editor settings for session files."""
        return {"source": self.source, "text": self.text_edit.text(), "method": self.method,
                "oracle": self.oracle_box.isChecked()}

    def apply_settings(self, d: dict) -> None:
        if d.get("source"):
            self.set_source(d["source"])
        self.text_edit.setText(d.get("text", ""))
        if d.get("method") and self.method_box.findData(d["method"]) >= 0:
            self.set_method(d["method"])
        self.oracle_box.setChecked(bool(d.get("oracle", True)))

    def close_view(self) -> None:
        disconnect_all(self._connections)

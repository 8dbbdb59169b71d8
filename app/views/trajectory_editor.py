"""Trajectory editor: a phone timeline with draggable targets, a method chooser, Synthesise and Play.

Targets come from a corpus utterance (its phone mid-points, with their oracle
states: the paper's Fig. 3 experiment), typed English text, a phone string with
durations (``p 0.08 ax 0.05 ...``) or a TextGrid / .lab file, and from clicked
states: "Add clicked state" (Ctrl+T) inserts a target holding the selected state at
the playback cursor, or after the last target. Dragging a target marker moves its
frame, inside its phone interval (:mod:`app.models.target_editing`); "Remove target" (Delete)
and "Reset targets" (back to the targets as loaded) complete the edits, each one a
command on :attr:`TrajectoryEditor.undo_stack` (the window's Edit > Undo / Redo).
The timeline zooms (wheel, + / -, Fit), shows time in ms, and with the keyboard focus
plays (Space) and steps (Left / Right) through :class:`app.models.state.AppState`'s playback.
Under it, where the utterance has audio, its waveform and wide-band spectrogram
(:mod:`app.views.sound_panel`, computed in a worker by :mod:`app.views.sound_track`)
scroll and zoom with it and carry the same playback cursor; "Sound" hides them.
The synthetic trajectory is drawn red in the manifold view and played beside the
original in the lip view; for an utterance the error against the captured original
is shown, and every synthesis warning is listed under the timeline.
"""
from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

from app.models.target_editing import remove_target
from app.models.trajectories import METHOD_LABELS, synthesize_targets, trajectory_error
from app.views._common import READOUT_INTERVAL_S, Throttle, connect_all, disconnect_all
from app.views.phone_timeline import PhoneTimeline
from app.views.sound_panel import SoundPanel
from app.views.sound_track import SoundTrack

__all__ = ["TrajectoryEditor", "TargetsEdit", "ZOOM_RANGE", "ADD_STATE_SHORTCUT", "REMOVE_SHORTCUT"]

SOURCES = (("utterance", "Utterance"), ("text", "Text"), ("phones", "Phones + durations"), ("textgrid", "TextGrid"))
ADD_STATE_SHORTCUT = "Ctrl+T"
REMOVE_SHORTCUT = "Delete"
#: timeline zoom: times the width that shows the whole trajectory
ZOOM_RANGE = (1.0, 64.0)


class TargetsEdit(QtGui.QUndoCommand):
    """One edit of the key targets (move, add, remove, reset) on the editor's undo stack."""

    def __init__(self, editor, before, after, text: str):
        super().__init__(text)
        self.editor, self.before, self.after = editor, before, after

    def redo(self):
        self.editor._apply_targets(self.after, f"{self.text()}: press Synthesise")

    def undo(self):
        self.editor._apply_targets(self.before, f"undone: {self.text()}")


# ============================================================================ the editor
class TrajectoryEditor(QtWidgets.QWidget):
    """Build targets, synthesise, play and compare; bound to an :class:`app.models.state.AppState`."""

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.state = state
        self.targets = None
        self.loaded_targets = None  # as loaded: what Reset targets goes back to
        self.undo_stack = QtGui.QUndoStack(self)
        self.zoom = 1.0
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
        self.remove_btn = QtWidgets.QPushButton("Remove target")
        self.remove_btn.setToolTip(f"Remove the chosen target (click its triangle first; {REMOVE_SHORTCUT} in the "
                                   "timeline)")
        self.reset_btn = QtWidgets.QPushButton("Reset targets")
        self.reset_btn.setToolTip("Back to the targets as loaded (undo with Ctrl+Z)")
        self.zoom_in_btn = QtWidgets.QToolButton()
        self.zoom_in_btn.setText("+")
        self.zoom_in_btn.setToolTip("Zoom the timeline in (or the mouse wheel over it)")
        self.zoom_out_btn = QtWidgets.QToolButton()
        self.zoom_out_btn.setText("−")
        self.zoom_out_btn.setToolTip("Zoom the timeline out")
        self.fit_btn = QtWidgets.QToolButton()
        self.fit_btn.setText("Fit")
        self.fit_btn.setToolTip("Show the whole trajectory")
        self.method_box = QtWidgets.QComboBox()
        self.synth_btn = QtWidgets.QPushButton("Synthesise")
        self.play_btn = QtWidgets.QPushButton("Play")
        self.readout = QtWidgets.QLabel("")
        self.readout.setTextInteractionFlags(QtCore.Qt.TextInteractionFlag.TextSelectableByMouse)
        self.readout.setWordWrap(True)
        # the phone tiers and the sound under them share one scrolled strip: one width, one scroll bar
        self.tracks = QtWidgets.QWidget()
        self.timeline = PhoneTimeline(self.tracks)
        self.sound = SoundPanel(self.tracks)
        self.sound.move(0, PhoneTimeline.HEIGHT)
        self.sound.hide()
        self.sound_track = SoundTrack(self.sound, state, parent=self)
        self.sound_box = QtWidgets.QCheckBox("Sound")
        self.sound_box.setChecked(True)
        self.sound_box.setToolTip("Show the utterance's waveform and wide-band spectrogram under the phones "
                                  "(where it has audio)")
        self._min_height_without_sound = None
        self.scroll = QtWidgets.QScrollArea()
        self.scroll.setWidget(self.tracks)
        self.scroll.setWidgetResizable(False)
        self.scroll.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAsNeeded)
        self.scroll.setVerticalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self._layout_tracks()
        self.scroll.setMinimumWidth(200)
        self.scroll.viewport().installEventFilter(self)
        self.warnings_list = QtWidgets.QListWidget()
        self.warnings_list.setToolTip("Every warning of the last synthesis")
        self.warnings_list.setMaximumHeight(72)
        self.warnings_list.setVisible(False)

        row1 = QtWidgets.QHBoxLayout()
        for w in (QtWidgets.QLabel("Input:"), self.source_box, self.utt_box, self.text_edit, self.browse_btn,
                  self.oracle_box, self.load_btn, self.add_state_btn):
            row1.addWidget(w)
        row1.setStretchFactor(self.text_edit, 1)
        row1.addStretch(0)
        row2 = QtWidgets.QHBoxLayout()
        for w in (QtWidgets.QLabel("Method:"), self.method_box, self.synth_btn, self.play_btn, self.remove_btn,
                  self.reset_btn, QtWidgets.QLabel("Zoom:"), self.zoom_out_btn, self.zoom_in_btn, self.fit_btn,
                  self.sound_box):
            row2.addWidget(w)
        row2.addWidget(self.readout, 1)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.setSpacing(3)
        lay.addLayout(row1)
        lay.addWidget(self.scroll)
        lay.addWidget(self.warnings_list)
        lay.addLayout(row2)
        lay.addStretch(1)

        self.source_box.currentIndexChanged.connect(lambda _i: self._sync_inputs())
        self.utt_box.activated.connect(lambda _i: self.load())
        self.text_edit.returnPressed.connect(self.load)
        self.browse_btn.clicked.connect(self._browse)
        self.load_btn.clicked.connect(self.load)
        self.add_state_btn.clicked.connect(self.add_selected_state)
        self.oracle_box.toggled.connect(lambda _on: self.load() if self.source == "utterance" else None)
        self.synth_btn.clicked.connect(self.synthesize)
        self.play_btn.clicked.connect(lambda: self.state.set_playing(True))
        self.remove_btn.clicked.connect(self.remove_selected)
        self.reset_btn.clicked.connect(self.reset_targets)
        self.zoom_in_btn.clicked.connect(lambda: self.zoom_by(1.25))
        self.zoom_out_btn.clicked.connect(lambda: self.zoom_by(0.8))
        self.fit_btn.clicked.connect(lambda: self.set_zoom(1.0))
        self.timeline.targetsChanged.connect(self._on_dragged)
        self.timeline.selectionChanged.connect(lambda _i: self._sync_buttons())
        self.timeline.deleteRequested.connect(self.remove_selected)
        self.timeline.playToggled.connect(self.toggle_playing)
        self.timeline.stepRequested.connect(self.step)
        self.timeline.zoomRequested.connect(lambda f, x: self.zoom_by(f, x))
        self.sound_box.toggled.connect(lambda _on: self._layout_tracks())
        self.sound_track.changed.connect(lambda _has: self._layout_tracks())
        ev = state.events
        # the cursor follows playback a few times a second (each repaint composes the whole window)
        self._cursor_readout = Throttle(self._set_cursor, READOUT_INTERVAL_S, parent=self)
        self._connections = [(ev.manifold, lambda _m: self.rebuild()), (ev.playback, self._cursor_readout),
                             (ev.utterance, self._on_utterance),
                             (ev.trajectory, lambda _o, syn: self._show_warnings(syn)),
                             (ev.state, lambda st: self.add_state_btn.setEnabled(st is not None))]
        connect_all(self._connections)
        self.rebuild()  # fills the methods once a manifold is there

    # ------------------------------------------------------------------ setup
    def _fill_methods(self):
        try:
            from engine.synthesis.method_choice import BEST
            from engine.synthesis.methods import METHODS
        except ImportError as exc:  # synthesis unavailable: say so, keep the rest working
            BEST, METHODS = None, ()
            self.readout.setText(f"synthesis unavailable: {exc}")
        for m in ((BEST,) if BEST else ()) + tuple(METHODS):
            self.method_box.addItem(METHOD_LABELS.get(m, m), m)
        if BEST:
            self.method_box.setItemData(0, "The method measured best on this corpus's own validation split for the "
                                           "kind of targets loaded (measured once per corpus, then cached); the "
                                           "readout names it", QtCore.Qt.ItemDataRole.ToolTipRole)

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
            # engine.synthesis.viterbi pulls in scikit-learn (seconds at start-up); by the time a manifold
            # is loaded it is imported already, so the empty window opens without it
            self._fill_methods()
        self.synthesizers = {}
        self.targets = None
        self.loaded_targets = None
        self.undo_stack.clear()
        self.timeline.set_targets(None)
        self.sound_track.clear_cache()
        self._sync_buttons()
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
        from engine.phonetics import targets as T

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
        self.edit_targets(tg, f"add state {self.state.state}")
        self.readout.setText(f"state {self.state.state} added as a target: {len(tg.targets)} targets over "
                             f"{tg.n_frames} frames; press Synthesise")
        return True

    def _show_error(self, exc) -> bool:
        import html

        from app.user_messages import user_message

        text = user_message(exc, doing="make targets") if isinstance(exc, BaseException) else str(exc)
        self.readout.setText(f"<span style='color:#b00'>{html.escape(text)}</span>")
        return False

    def _set_targets(self, targets, message: str) -> bool:
        """New targets from an input (Load): the baseline of Reset; the undo history starts again."""
        self.undo_stack.clear()
        self.loaded_targets = targets
        self.timeline.select(None)  # a chosen target of other targets means nothing here
        self._apply_targets(targets, message)
        return True

    def restore_targets(self, targets, message: str = "targets restored from the session") -> None:
        """Targets from a session file (as edited then): shown, with a fresh undo history."""
        self._set_targets(targets, message)

    def _apply_targets(self, targets, message: str) -> None:
        self.targets = targets
        self.timeline.set_targets(targets)
        if targets is not None:
            self.sound.set_span(targets.n_frames, targets.rate, targets.phones)
        self.sound_track.show(None if targets is None else targets.utterance)
        self._layout_tracks()
        self.readout.setText(message)
        self._sync_buttons()

    def edit_targets(self, targets, text: str) -> None:
        """Replace the targets by an edit ``text`` ("move target 3") that Edit > Undo takes back."""
        self.undo_stack.push(TargetsEdit(self, self.targets, targets, text))

    def _sync_buttons(self) -> None:
        t = self.targets
        self.remove_btn.setEnabled(t is not None and self.timeline.selected is not None and len(t.targets) > 1)
        self.reset_btn.setEnabled(self.loaded_targets is not None and t != self.loaded_targets)

    def _on_dragged(self, before, after):
        i = self.timeline.selected
        label = after.targets[i].label if i is not None else ""
        self.undo_stack.push(TargetsEdit(self, before, after, f"move target {'' if i is None else i + 1}"
                                                              f"{f' ({label})' if label else ''}"))

    def remove_selected(self) -> bool:
        """Remove the target chosen in the timeline (an undoable edit)."""
        i = self.timeline.selected
        if self.targets is None or i is None:
            return self._show_error("choose a target first: click its triangle in the timeline")
        try:
            tg = remove_target(self.targets, i)
        except (ValueError, IndexError) as exc:
            return self._show_error(exc)
        self.timeline.select(None)
        self.edit_targets(tg, f"remove target {i + 1}")
        return True

    def reset_targets(self) -> bool:
        """Back to the targets as loaded (an undoable edit)."""
        if self.loaded_targets is None or self.targets == self.loaded_targets:
            return False
        self.edit_targets(self.loaded_targets, "reset targets")
        return True

    # ------------------------------------------------------------------ timeline zoom and keys
    def set_zoom(self, zoom: float, anchor_x: float | None = None) -> float:
        """Show the timeline ``zoom`` times as wide as the view (clamped to :data:`ZOOM_RANGE`).

        ``anchor_x`` (a pixel of the timeline) stays under the same time.
        """
        lo, hi = ZOOM_RANGE
        tl, bar = self.timeline, self.scroll.horizontalScrollBar()
        anchor = None
        if anchor_x is not None:
            anchor = (tl.frame_at(anchor_x), anchor_x - bar.value())  # (time, pixel on screen)
        self.zoom = float(min(max(zoom, lo), hi))
        view_w = self.scroll.viewport().width()
        width = max(int(round(view_w * self.zoom)), 1)
        tl.resize(width, PhoneTimeline.HEIGHT)
        self.sound.resize(width, SoundPanel.HEIGHT)
        self.tracks.resize(width, self._tracks_height())
        if anchor is not None and tl.targets is not None:
            bar.setValue(int(round(tl._x(anchor[0]) - anchor[1])))
        return self.zoom

    def _tracks_height(self) -> int:
        return PhoneTimeline.HEIGHT + (SoundPanel.HEIGHT if self.sound.isVisibleTo(self.tracks) else 0)

    def _layout_tracks(self) -> None:
        """Show the sound under the phones when asked for and the utterance has audio; size the strip."""
        show = self.sound_box.isChecked() and self.sound_track.wanted is not None
        self.sound.setVisible(show)
        h = self._tracks_height()
        self.tracks.resize(self.timeline.width(), h)
        self.scroll.setFixedHeight(h + self.scroll.horizontalScrollBar().sizeHint().height() + 4)
        # the dock grows by the sound's height while it shows (an explicit minimum height, as the
        # window sets one, would otherwise clip it), and gives it back after
        if show and self._min_height_without_sound is None:
            self._min_height_without_sound = self.minimumHeight()
        if self._min_height_without_sound is not None:
            need = self.layout().totalMinimumSize().height() if show else 0
            self.setMinimumHeight(max(self._min_height_without_sound, need))
            if not show:
                self._min_height_without_sound = None

    def _set_cursor(self, frame) -> None:
        self.timeline.set_cursor(frame)
        self.sound.set_cursor(frame)

    def zoom_by(self, factor: float, anchor_x: float | None = None) -> float:
        if anchor_x is None:
            bar = self.scroll.horizontalScrollBar()
            anchor_x = bar.value() + self.scroll.viewport().width() / 2
        return self.set_zoom(self.zoom * factor, anchor_x)

    def eventFilter(self, obj, ev):
        if obj is self.scroll.viewport() and ev.type() == QtCore.QEvent.Type.Resize:
            self.set_zoom(self.zoom)
        return super().eventFilter(obj, ev)

    def toggle_playing(self) -> None:
        """Space in the timeline: play or pause (through the state, as the Play buttons do)."""
        self.state.set_playing(not self.state.playing)

    def step(self, delta: int) -> None:
        """Left / Right in the timeline: pause and show the previous / next frame."""
        s = self.state
        if s.n_playback == 0:
            return
        s.set_playing(False)
        k = 0 if s.playback is None else s.playback + int(delta)
        s.set_playback(min(max(k, 0), s.n_playback - 1))

    # ------------------------------------------------------------------ synthesis
    def synthesize(self):
        """Synthesise the current targets with the chosen method in a worker thread."""
        from app.user_messages import plain_errors
        from app.workers import DIALOG_DELAY_MS, run_task

        if self._runner is not None and self._runner.state == "running":
            return self._runner  # one synthesis at a time
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
            data, _traj = synthesize_targets(m, tg, method, self.synthesizers, progress=progress)
            err = trajectory_error(m, data, orig) if orig is not None else None
            progress("synthesising", 1, 1)
            return data, err

        self._runner = run_task(plain_errors(task, doing=f"synthesise with {method}"), parent=self,
                                title="Synthesising", on_done=self._on_synth,
                                on_error=self._on_synth_error, on_cancel=lambda: self._on_synth_error("cancelled", ""))
        # most syntheses take a few ms: nothing is repainted before their result (a repaint composes the
        # window, ~20 ms in software GL); one still running when its dialog opens shows it here too
        QtCore.QTimer.singleShot(DIALOG_DELAY_MS, self, lambda r=self._runner: self._show_busy(r, method))
        return self._runner

    def _show_busy(self, runner, method: str) -> None:
        if runner is self._runner and runner.state == "running":
            self.synth_btn.setEnabled(False)
            self.readout.setText(f"synthesising with {method}…")

    def _on_synth(self, result):
        data, err = result
        self.synth_btn.setEnabled(True)
        self.state.set_trajectories(synthetic=data)
        note = (data.extra or {}).get("method_note")
        text = (f"{note}; " if note else "") + f"{data.label}: {len(data)} frames"
        if err is not None:
            text += (f"; error vs original: RMSE(X) {err['rmse_x']:.4g}, per-point mean {err['mean_point_error']:.3g} "
                     f"/ max {err['max_point_error']:.3g} (corpus units)")
        warns = data.extra.get("warnings") or []
        if warns:
            text += f"; {len(warns)} warning{'s' * (len(warns) != 1)}, listed above"
        self.last_error = err
        self.readout.setText(text)

    def _show_warnings(self, synthetic) -> None:
        """List every warning of the synthetic trajectory shown (none: the list hides)."""
        warns = [] if synthetic is None else [str(w) for w in (synthetic.extra or {}).get("warnings") or []]
        self.warnings_list.clear()
        for w in warns:
            self.warnings_list.addItem(f"⚠ {w}")
        self.warnings_list.setVisible(bool(warns))

    def _on_synth_error(self, message, _tb=""):
        self.synth_btn.setEnabled(True)
        import html

        self.readout.setText(f"<span style='color:#b00'>synthesis failed: {html.escape(message)}</span>")

    def settings(self) -> dict:
        """Editor settings for session files."""
        return {"source": self.source, "text": self.text_edit.text(), "method": self.method,
                "oracle": self.oracle_box.isChecked(), "sound": self.sound_box.isChecked()}

    def apply_settings(self, d: dict) -> None:
        if d.get("source"):
            self.set_source(d["source"])
        self.text_edit.setText(d.get("text", ""))
        if d.get("method") and self.method_box.findData(d["method"]) >= 0:
            self.set_method(d["method"])
        self.oracle_box.setChecked(bool(d.get("oracle", True)))
        self.sound_box.setChecked(bool(d.get("sound", True)))

    def close_view(self) -> None:
        disconnect_all(self._connections)
        self.sound_track.stop()

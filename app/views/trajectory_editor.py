"""Trajectory editor: a phone timeline with draggable targets, a method chooser, Synthesise and Play.

Targets come from a corpus utterance (its phone mid-points, with their oracle
states: the paper's Fig. 3 experiment), typed English text, a phone string with
durations (``p 0.08 ax 0.05 ...``) or a TextGrid / .lab file, and from clicked
states: "Add clicked state" (Ctrl+T) inserts a target holding the selected state at
the playback cursor, or after the last target. Dragging a target marker moves its
frame, inside its phone interval (:mod:`app.models.target_editing`); "Remove target" (Delete)
and "Reset targets" (back to the targets as loaded) complete the edits, each one a
command on :attr:`TrajectoryEditor.undo_stack` (the window's Edit > Undo / Redo).
The timeline works as Praat's editors do (:mod:`app.views.editor.timeline_control`): a click
sets the cursor and selects the state under it, a drag selects, Tab plays the selection,
Shift+Tab from the cursor, Space plays or pauses, Ctrl+I / O / N / A zoom; phone and word
boundaries drag, each edit undoable, and "Save TextGrid…" writes the tiers. Under the tiers,
where the utterance has audio, its waveform and wide-band spectrogram
(:mod:`app.views.sound_panel`, computed in a worker by :mod:`app.views.sound_track`)
scroll and zoom with it and carry the same cursor; "Sound" hides them, and the editor gives
their room back.
The synthetic trajectory is drawn red in the manifold view and played beside the
original in the lip view; for an utterance the error against the captured original
is shown, and every synthesis warning is listed under the timeline.
"""
from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

from app.models.target_editing import remove_target
from app.models.trajectories import METHOD_LABELS, synthesize_targets, trajectory_error
from app.views._common import READOUT_INTERVAL_S, Throttle, connect_all, disconnect_all, elided_label
from app.views.editor.commands import TargetsEdit
from app.views.editor.signals_control import SignalsControl
from app.views.editor.timeline_control import ZOOM_RANGE, TimelineControl
from app.views.flow_layout import FlowLayout

__all__ = ["TrajectoryEditor", "TargetsEdit", "ZOOM_RANGE", "ADD_STATE_SHORTCUT", "REMOVE_SHORTCUT"]

SOURCES = (("utterance", "Utterance"), ("text", "Text"), ("phones", "Phones + durations"), ("textgrid", "TextGrid"))
ADD_STATE_SHORTCUT = "Ctrl+T"
REMOVE_SHORTCUT = "Delete"


def _words_up_to(text: str, n: int) -> str:
    """``text``'s whole words up to ``n`` characters, "…" where it goes on (never a word cut)."""
    text = " ".join(str(text).split())
    if len(text) <= n:
        return text
    cut = text[:n + 1].rsplit(" ", 1)[0] if " " in text[:n + 1] else text[:n]
    return cut.rstrip(" ,.;:") + "…"


# ============================================================================ the editor
class TrajectoryEditor(TimelineControl, SignalsControl, QtWidgets.QWidget):
    """Build targets, synthesise, play and compare; bound to an :class:`app.models.state.AppState`.

    .. rubric:: Signals

    heightWanted(int)
        The height the editor needs changed (the sound shown or hidden): the window sizes its dock.
    notice(str)
        Something the window says once in its status bar (why a synthesis of text is silent).
    """

    heightWanted = QtCore.Signal(int)
    #: a note for the window's status bar (a synthesis that stays silent, and why)
    notice = QtCore.Signal(str)

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.state = state
        self.targets = None
        self.words = ()  # the word tier shown over the phones (() where the input has none)
        self.loaded_words = ()  # the word tier as loaded: what Reset targets goes back to
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
        # whole names ("s0001 — Ranch ..."), not "s0001 — Ranc": as wide as the longest, up to 48 characters
        self.utt_box.setSizeAdjustPolicy(QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToContents)
        self.utt_box.setMinimumContentsLength(16)
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
        self.method_box.setSizeAdjustPolicy(QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToContents)
        self.synth_btn = QtWidgets.QPushButton("Synthesise")
        self.play_btn = QtWidgets.QPushButton("Play")
        self.save_tiers_btn = QtWidgets.QPushButton("Save TextGrid…")
        self.save_tiers_btn.setToolTip("Write the tiers as they are now (phones, words, the targets) as a Praat "
                                       "TextGrid")
        # buttons never take the keyboard focus by a click: Space after Synthesise plays, never synthesises again
        for b in (self.browse_btn, self.load_btn, self.add_state_btn, self.remove_btn, self.reset_btn,
                  self.synth_btn, self.play_btn, self.save_tiers_btn, self.zoom_in_btn, self.zoom_out_btn,
                  self.fit_btn):
            b.setFocusPolicy(QtCore.Qt.FocusPolicy.TabFocus)
        # one line, elided (the whole text in its tooltip): a long message never grows the editor
        self.readout = elided_label("")
        self.readout.setMinimumWidth(200)
        self.readout.setMaximumWidth(560)
        self.readout.setSizePolicy(QtWidgets.QSizePolicy.Policy.Preferred, QtWidgets.QSizePolicy.Policy.Fixed)
        # the tiers and the sound under them share one scrolled strip: one width, one scroll bar
        self._make_tracks(state)
        self.warnings_list = QtWidgets.QListWidget()
        self.warnings_list.setToolTip("Every warning of the last synthesis")
        self.warnings_list.setMaximumHeight(72)
        self.warnings_list.setVisible(False)

        self.text_edit.setMinimumWidth(260)
        # the controls in groups that wrap to a new row (never clipped): two rows at 1280 px
        bar = FlowLayout(spacing=10, margins=(0, 0, 0, 0), row_spacing=3)
        for group in ((QtWidgets.QLabel("Input:"), self.source_box, self.utt_box, self.text_edit, self.browse_btn,
                       self.oracle_box, self.load_btn, self.add_state_btn),
                      (QtWidgets.QLabel("Method:"), self.method_box, self.synth_btn, self.play_btn),
                      (self.remove_btn, self.reset_btn, self.save_tiers_btn),
                      (QtWidgets.QLabel("Zoom:"), self.zoom_out_btn, self.zoom_in_btn, self.fit_btn, self.sound_box,
                       self.signals_btn),
                      (self.readout,)):
            bar.add_group(group)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(4, 2, 4, 2)
        lay.setSpacing(2)
        lay.addLayout(bar)
        lay.addWidget(self.scroll)
        lay.addWidget(self.warnings_list)
        self._layout_tracks()

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
        self.save_tiers_btn.clicked.connect(self.save_textgrid_dialog)
        self.zoom_in_btn.clicked.connect(lambda: self.zoom_by(1.25))
        self.zoom_out_btn.clicked.connect(lambda: self.zoom_by(0.8))
        self.fit_btn.clicked.connect(lambda: self.set_zoom(1.0))
        self.timeline.targetsChanged.connect(self._on_dragged)
        self.timeline.selectionChanged.connect(lambda _i: self._sync_buttons())
        self.timeline.deleteRequested.connect(self.remove_selected)
        self.timeline.stepRequested.connect(self.step)
        self.timeline.zoomRequested.connect(lambda f, x: self.zoom_by(f, x))
        ev = state.events
        # the cursor follows playback a few times a second (each repaint composes the whole window)
        self._cursor_readout = Throttle(self._set_cursor, READOUT_INTERVAL_S, parent=self)
        self._connections = [(ev.manifold, lambda _m: self.rebuild()), (ev.playback, self._cursor_readout),
                             (ev.utterance, self._on_utterance),
                             (ev.trajectory, lambda _o, syn: self._show_warnings(syn)),
                             (ev.state, lambda st: self.add_state_btn.setEnabled(st is not None)),
                             (ev.palette, lambda _p: (self.timeline.update(), self._show_signals()))]
        connect_all(self._connections)
        self.rebuild()  # fills the methods once a manifold is there

    # ------------------------------------------------------------------ setup
    def _fill_methods(self):
        try:
            from engine.synthesis.method_choice import BEST
            from engine.synthesis.methods import METHODS
        except ImportError as exc:  # synthesis unavailable: say so, keep the rest working
            BEST, METHODS = None, ()
            self.say(f"synthesis unavailable: {exc}")
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
        self.words, self.loaded_words = (), ()
        self.timeline.set_targets(None, ())
        self.set_time_selection(None)
        self.sound_track.clear_cache()
        self._signals_on_manifold()
        self._sync_buttons()
        self.utt_box.blockSignals(True)
        self.utt_box.clear()
        if m is not None:
            for u in m.corpus_.utterances:
                self.utt_box.addItem(f"{u.id}" + (f" — {_words_up_to(u.text, 30)}" if u.text else ""), u.id)
                self.utt_box.setItemData(self.utt_box.count() - 1, f"{u.id}: {u.text}",
                                         QtCore.Qt.ItemDataRole.ToolTipRole)
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
            words = ()
            if s == "utterance":
                uid = self.utt_box.currentData()
                if uid is None:
                    raise ValueError("the corpus has no utterances")
                tg = T.targets_from_utterance(m, uid, on_collision="merge")
                words = tuple(m.corpus_.utterance(uid).words)
                if not self.oracle_box.isChecked():
                    tg = tg.phones_only()
                if self.state.utterance != uid:
                    self.state.set_utterance(uid)
                else:
                    self.state.set_trajectories(synthetic=None)
            elif s == "text":
                from app.models.tier_editing import text_words

                tg = T.targets_from_text(m, text, on_collision="merge")
                words = text_words(text, tg.phones)
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
                                     f"({tg.n_frames / tg.rate:.2f} s) from {tg.source}", words=words)

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
        self.say(f"state {self.state.state} added as a target: {len(tg.targets)} targets over "
                             f"{tg.n_frames} frames; press Synthesise")
        return True

    def say(self, text: str, *, error: bool = False) -> None:
        """Show ``text`` in the readout line (in red for an error; elided, whole in its tooltip)."""
        self.readout.setStyleSheet("color: #b00" if error else "")
        self.readout.setText(text)

    def _show_error(self, exc) -> bool:
        from app.user_messages import user_message

        text = user_message(exc, doing="make targets") if isinstance(exc, BaseException) else str(exc)
        self.say(text, error=True)
        return False

    def _set_targets(self, targets, message: str, words=()) -> bool:
        """New targets from an input (Load): the baseline of Reset; the undo history starts again."""
        self.undo_stack.clear()
        self.loaded_targets = targets
        self.loaded_words = tuple(words)
        self.timeline.select(None)  # a chosen target of other targets means nothing here
        self.set_time_selection(None)
        self._apply_targets(targets, message, words=tuple(words))
        return True

    def restore_targets(self, targets, message: str = "targets restored from the session", words=()) -> None:
        """Targets from a session file (as edited then): shown, with a fresh undo history."""
        self._set_targets(targets, message, words=words)

    def _apply_targets(self, targets, message: str, words=None) -> None:
        """Show ``targets`` (and the word tier ``words``; None keeps the one shown)."""
        self.targets = targets
        if words is not None:
            self.words = tuple(words)
        self.timeline.set_targets(targets, self.words)
        if targets is not None:
            self.sound.set_span(targets.n_frames, targets.rate, targets.phones)
        self.sound_track.show(None if targets is None else targets.utterance)
        self._show_signals()  # lays the strip out
        self.say(message)
        self._sync_buttons()

    def edit_targets(self, targets, text: str) -> None:
        """Replace the targets by an edit ``text`` ("move target 3") that Edit > Undo takes back."""
        self.undo_stack.push(TargetsEdit(self, self.targets, targets, text))

    def _sync_buttons(self) -> None:
        t = self.targets
        self.remove_btn.setEnabled(t is not None and self.timeline.selected is not None and len(t.targets) > 1)
        self.reset_btn.setEnabled(self.loaded_targets is not None and (
            t != self.loaded_targets or self.words != self.loaded_words))
        self.save_tiers_btn.setEnabled(t is not None)

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
        """Back to the targets and tiers as loaded (an undoable edit)."""
        loaded_words = self.loaded_words
        if self.loaded_targets is None or (self.targets == self.loaded_targets and self.words == loaded_words):
            return False
        self.undo_stack.push(TargetsEdit(self, self.targets, self.loaded_targets, "reset targets", self.words,
                                         loaded_words))
        return True

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
            self.say("no synthesis method available")
            return None
        orig = self.state.original if (self.source == "utterance" and self.state.original is not None
                                       and len(self.state.original) == tg.n_frames) else None
        spoken = self.text_edit.text().strip() if self.source == "text" else ""

        def task(progress):
            progress("synthesising", 0, 1)
            data, _traj = synthesize_targets(m, tg, method, self.synthesizers, progress=progress)
            err = trajectory_error(m, data, orig) if orig is not None else None
            progress("synthesising", 1, 1)
            if spoken:  # typed text speaks (espeak-ng), on the synthesis's phone times
                from app.files.sound import SoundNote, speech_for_targets

                progress("speaking the text", 0, 1)
                try:
                    data.extra["audio"] = str(speech_for_targets(tg, spoken))
                except SoundNote as exc:
                    data.extra["sound_note"] = str(exc)
                progress("speaking the text", 1, 1)
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
            self.say(f"synthesising with {method}…")

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
        if data.extra.get("audio"):
            text += "; with the text spoken (Play)"
        elif data.extra.get("sound_note"):
            text += f"; {data.extra['sound_note']}"
            self.notice.emit(data.extra["sound_note"])
        self.last_error = err
        self.say(text)

    def _show_warnings(self, synthetic) -> None:
        """List every warning of the synthetic trajectory shown (none: the list hides)."""
        warns = [] if synthetic is None else [str(w) for w in (synthetic.extra or {}).get("warnings") or []]
        self.warnings_list.clear()
        for w in warns:
            self.warnings_list.addItem(f"⚠ {w}")
        self.warnings_list.setVisible(bool(warns))

    def _on_synth_error(self, message, _tb=""):
        self.synth_btn.setEnabled(True)
        self.say(f"synthesis failed: {message}", error=True)

    def settings(self) -> dict:
        """Editor settings for session files."""
        return {"source": self.source, "text": self.text_edit.text(), "method": self.method,
                "oracle": self.oracle_box.isChecked(), "sound": self.sound_box.isChecked(),
                "words": [[float(w.start), float(w.end), str(w.label)] for w in self.words]}

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

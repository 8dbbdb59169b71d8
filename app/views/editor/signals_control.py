"""The derived signals and gestural landmarks under the editor's timeline (a mixin of the editor).

Under the tiers and the sound, the time strip shows the gestures of one track as a point tier
(:class:`app.views.gesture_tier.GestureTier`) and the channels the user chose
(:class:`app.views.track_channels.TrackChannels`), from a Qt-free
:class:`app.models.signals.Signals` per corpus. They share the timeline's cursor, selection,
zoom and keys (a click selects the state under it). The **Signals** menu chooses the channels,
the low-pass cut-off, the track whose gestures are found; it finds them again and exports them
as ``lipspace table --gestures`` writes them (the per-gesture table, TextGrids with a gesture
tier). A landmark dragged, marked missing or a gesture removed is one edit on
:attr:`gesture_undo_stack`, part of the window's one undo history; the state's
:attr:`app.models.state.AppState.gestures` follows every edit (the manifold view marks them).
"""
from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

from app.models.signals import LANDMARK_WORDS, Signals, default_lowpass, landmark_colour
from app.views.gesture_tier import GestureTier
from app.views.track_channels import TrackChannels

__all__ = ["SignalsControl", "GestureEdit", "LOWPASS_CHOICES", "CHANNEL_GROUPS"]

#: the cut-offs the Signals menu offers (Hz), beside "Other…" and "None"
LOWPASS_CHOICES = (10.0, 15.0, 20.0, 25.0)
#: the Signals menu's channel groups: (title, test on the track name)
CHANNEL_GROUPS = (("Lips", lambda n: n.startswith("lip_")), ("Tangential velocity", lambda n: n.startswith("speed_")),
                  ("Position along the talker's axes", lambda n: n.rsplit("_", 1)[-1] in ("forward", "up", "left")),
                  ("Sensor quality", lambda n: n.startswith(("rms_", "error_"))))


class GestureEdit(QtGui.QUndoCommand):
    """One edit of the landmarks (done already by the :class:`GestureEditor` when pushed); undo and redo step
    the editor's own history, which every landmark edit goes through in the same order."""

    def __init__(self, gesture_editor, text: str):
        super().__init__(text)
        self.gesture_editor = gesture_editor
        self._done = True

    def redo(self):
        if self._done:
            self._done = False
            return
        self.gesture_editor.redo()

    def undo(self):
        self.gesture_editor.undo()


class SignalsControl:
    """Channels and landmarks of :class:`app.views.trajectory_editor.TrajectoryEditor` (module docstring)."""

    def _make_signals(self, state) -> None:
        self.signals = None
        self._signals_pending = None  # a session's settings waiting for its manifold
        self._finder = None
        self.gesture_undo_stack = QtGui.QUndoStack(self)
        self.gesture_tier = GestureTier(self.tracks)
        self.channels = TrackChannels(self.tracks)
        self.signal_rows = (self.gesture_tier, self.channels)
        self.gesture_tier.landmarkMoved.connect(self.move_landmark)
        self.gesture_tier.clearRequested.connect(self.clear_landmark)
        self.gesture_tier.removeRequested.connect(self.remove_gesture)
        self.signals_btn = QtWidgets.QToolButton()
        self.signals_btn.setText("Signals")
        self.signals_btn.setToolTip("Channels under the timeline (aperture, protrusion, velocities, positions, rms), "
                                    "the low-pass cut-off, the gestural landmarks and their export")
        self.signals_btn.setPopupMode(QtWidgets.QToolButton.ToolButtonPopupMode.InstantPopup)
        self.signals_btn.setFocusPolicy(QtCore.Qt.FocusPolicy.TabFocus)
        self.signals_menu = QtWidgets.QMenu(self.signals_btn)
        self.signals_menu.aboutToShow.connect(self._fill_signals_menu)
        self.signals_btn.setMenu(self.signals_menu)

    # ------------------------------------------------------------------ per corpus
    def _signals_on_manifold(self) -> None:
        """A new manifold: its signals (a session's settings where one waits), gestures found anew."""
        from app.models.signals import SignalsError

        m = self.state.manifold
        self.gesture_undo_stack.clear()
        self.signals = None
        if m is None:
            self._show_signals()
            return
        d, self._signals_pending = self._signals_pending, None
        try:
            self.signals = Signals.from_settings(m.corpus_, d) if d else Signals(m.corpus_)
        except SignalsError as exc:
            self.say(f"signals of the session not restored: {exc}", error=True)
            self.signals = Signals(m.corpus_)
            d = None
        self.signals.panel.changed.connect(self._on_channels_changed)
        # after the window has drawn the new manifold: the finder's imports (SciPy's signal package, half a
        # second) would otherwise share the interpreter with that first frame
        self._find_gestures(restore=d, after_events=True)

    def _find_gestures(self, restore=None, *, after_events: bool = False) -> None:
        """Find the gestures of the chosen track over the corpus in a worker (started at the event loop's next
        turn with ``after_events``); then restore a session's edits."""
        from app.user_messages import plain_errors
        from app.workers import run_task

        sig = self.signals
        self.gesture_undo_stack.clear()
        if self._finder is not None and self._finder.state == "running":
            self._finder.cancel()
        sig.use(None)
        self.state.set_gestures(None)
        if sig.gesture_track is None:
            self._show_signals()
            return
        self._show_signals(tier_message=f"finding the gestures of {sig.gesture_track}…")

        def done(gs, sig=sig):
            if sig is not self.signals:
                return  # another corpus since
            sig.use(gs)
            if restore:
                try:
                    sig.restore(restore)
                except ValueError as exc:
                    self.say(f"edited gestures of the session not restored: {exc}", error=True)
            sig.editor.changed.connect(self._on_gestures_changed)
            self.state.set_gestures(sig.gestures)
            self._show_signals()

        self._finder = run_task(plain_errors(sig.find, doing=f"find the gestures of {sig.gesture_track}"),
                                parent=self, title="Finding gestures", on_done=done, dialog=False,
                                after_events=after_events,
                                on_error=lambda msg, _tb: self._show_signals(tier_message=msg))

    def _on_channels_changed(self, why: str) -> None:
        if why == "lowpass" and self.signals is not None and self.signals.gesture_track is not None:
            if not self.signals.edited:  # found again at the new cut-off
                self._find_gestures()
                return
            self.say(f"the edited gestures keep the cut-off they were found at; Signals › Find gestures again finds "
                     f"them at {self._lowpass_text(self.signals.panel.lowpass_hz)}")
        self._show_signals()

    def _on_gestures_changed(self, _kind, _g) -> None:
        self.state.set_gestures(self.signals.gestures)
        self._show_signals()

    def _show_signals(self, tier_message: str = "") -> None:
        """Draw the channels and the landmarks of the utterance the timeline shows."""
        tg = self.targets
        uid = None if tg is None else tg.utterance
        for row in self.signal_rows:
            if tg is not None:
                row.set_span(tg.n_frames, tg.rate)
        sig, ed = self.signals, None if self.signals is None else self.signals.editor
        none = "no utterance: the channels and gestures are of a corpus utterance (Input: Utterance)"
        if sig is None or tg is None:
            self.channels.set_view(None)
            self.gesture_tier.set_gestures(None, None, None)
        elif uid is None:  # said once: on the channels' strip when there is one, else on the gesture tier
            self.channels.set_view(None, none if sig.panel.channels else "")
            self.gesture_tier.set_gestures(None, None, None, none if sig.gesture_track and not sig.panel.channels
                                           else "")
        else:
            self.channels.set_view(sig.panel.view(uid) if sig.panel.channels else None)
            message = tier_message or ("" if sig.gesture_track is None else "no gestures found")
            self.gesture_tier.set_gestures(ed, uid if ed is not None else None, self.state.palette, message)
            marks = {}
            if ed is not None and ed.gestures.track in sig.panel.channels:
                marks[ed.gestures.track] = [(t, landmark_colour(self.state.palette, name), name)
                                            for t, name, _g, _j in ed.points(uid)]
            self.channels.set_marks(marks)
        self.gesture_tier.setVisible(sig is not None and sig.gesture_track is not None
                                     and not (uid is None and sig.panel.channels))
        self.channels.setVisible(self.channels.wanted_height() > 0)
        self._layout_tracks()

    # ------------------------------------------------------------------ edits (each one undoable)
    def _gesture_edit(self, text: str, action):
        ed = self.signals.editor
        before = ed.gestures
        out = action(ed)
        if ed.gestures is not before:
            self.gesture_undo_stack.push(GestureEdit(ed, text))
        return out

    def move_landmark(self, gesture: int, landmark: int, time_s: float) -> float:
        """Move a landmark (clamped to its gesture's order), one undoable edit; returns its new time."""
        from engine.recordings.signals.gestures import LANDMARKS

        name = LANDMARKS[int(landmark)]
        return self._gesture_edit(f"move {name} of gesture {self.gesture_tier._number(gesture)}",
                                  lambda ed: ed.move(gesture, landmark, time_s))

    def clear_landmark(self, gesture: int, landmark: int) -> None:
        """Mark a landmark missing, one undoable edit."""
        from engine.recordings.signals.gestures import LANDMARKS

        self._gesture_edit(f"mark {LANDMARKS[int(landmark)]} missing", lambda ed: ed.clear(gesture, landmark))

    def remove_gesture(self, gesture: int) -> None:
        """Take a gesture out (a false detection), one undoable edit."""
        self.gesture_tier.choose(None)
        self._gesture_edit(f"remove gesture {self.gesture_tier._number(gesture)}", lambda ed: ed.remove(gesture))

    # ------------------------------------------------------------------ choices
    def set_channels(self, names) -> None:
        """Show the channels ``names`` in that order."""
        panel = self.signals.panel
        for n in list(panel.channels):
            if n not in names:
                panel.remove(n)
        for k, n in enumerate(names):
            panel.add(n, index=k)
            panel.move(n, k)

    def toggle_channel(self, name: str, on: bool) -> None:
        """Show (``on``) or stop showing channel ``name``."""
        panel = self.signals.panel
        if on:
            panel.add(name)
        elif name in panel.channels:
            panel.remove(name)

    def set_lowpass(self, hz) -> bool:
        """The channels' (and, unedited, the gestures') low-pass cut-off in Hz (None: raw); False with the reason
        said when the corpus's rate does not allow it."""
        try:
            self.signals.panel.set_lowpass(hz)
        except ValueError as exc:
            return self._show_error(exc)
        return True

    def set_gesture_track(self, track) -> None:
        """Find the gestures of ``track`` (None: no gesture tier); edits of the previous track's are dropped."""
        if track != self.signals.gesture_track:
            self.signals.gesture_track = track
            self._find_gestures()

    @staticmethod
    def _lowpass_text(hz) -> str:
        return "raw positions" if hz is None else f"{hz:g} Hz"

    def _fill_signals_menu(self) -> None:
        menu = self.signals_menu
        menu.clear()
        sig = self.signals
        if sig is None:
            menu.addAction("(open a corpus or manifold first)").setEnabled(False)
            return
        chans = menu.addMenu("Channels")
        for title, test in CHANNEL_GROUPS:
            names = [n for n in sig.panel.available if test(n)]
            if names:
                sub = chans.addMenu(title)
                for n in names:
                    a = sub.addAction(n, lambda on=False, n=n: self.toggle_channel(n, on))
                    a.setCheckable(True)
                    a.setChecked(n in sig.panel.channels)
        low = menu.addMenu(f"Low-pass cut-off: {self._lowpass_text(sig.panel.lowpass_hz)}")
        for hz in LOWPASS_CHOICES + (None,):
            a = low.addAction(self._lowpass_text(hz) + (" (default)" if hz == default_lowpass(sig.corpus.rate) else ""),
                              lambda _on=False, hz=hz: self.set_lowpass(hz))
            a.setEnabled(hz is None or hz < 0.5 * sig.corpus.rate)  # below the Nyquist frequency only
            a.setCheckable(True)
            a.setChecked(sig.panel.lowpass_hz == hz)
        low.addAction("Other…", self._ask_lowpass)
        ges = menu.addMenu("Gestures of")
        for t in [None] + sig.gesture_choices():
            a = ges.addAction(t or "none (no gesture tier)", lambda _on=False, t=t: self.set_gesture_track(t))
            a.setCheckable(True)
            a.setChecked(sig.gesture_track == t)
        again = menu.addAction("Find gestures again", self._find_again)
        again.setEnabled(sig.gesture_track is not None)
        menu.addSeparator()
        for text, slot in (("Export gesture table (CSV, Parquet)…", self.export_gesture_table_dialog),
                           ("Export TextGrids with the gesture tier…", self.export_gesture_textgrids_dialog)):
            menu.addAction(text, slot).setEnabled(sig.gestures is not None)

    def _ask_lowpass(self) -> None:
        hz, ok = QtWidgets.QInputDialog.getDouble(self, "Low-pass cut-off", "Cut-off (Hz), below half the frame "
                                                  f"rate ({self.signals.corpus.rate:g} Hz):",
                                                  self.signals.panel.lowpass_hz or 15.0, 0.5, 10000.0, 1)
        if ok:
            self.set_lowpass(hz)

    def _find_again(self) -> None:
        if self.signals.edited and QtWidgets.QMessageBox.question(
                self, "Lipspace", "Find the gestures again? The landmarks moved by hand go back to those found.") \
                != QtWidgets.QMessageBox.StandardButton.Yes:
            return
        self._find_gestures()

    # ------------------------------------------------------------------ exports
    def export_gesture_table(self, path):
        """Write one row per gesture as ``lipspace table --gesture-table`` does (and its sidecar); returns the files."""
        from engine.io.writers.tidy import write_frame_table
        from engine.manifold.lab_tables import gesture_table

        return write_frame_table(path, gesture_table(self.state.manifold, [self.signals.gestures],
                                                     source=str(self.state.source.get("path") or "")))

    def export_gesture_textgrids(self, directory, progress=None):
        """One TextGrid per utterance with the gesture tier, as ``lipspace table --gestures --textgrid`` writes."""
        from engine.manifold.frame_table import frame_table
        from engine.manifold.lab_tables import write_textgrids_with_gestures

        m = self.state.manifold
        table = frame_table(m, n_fx=0, source=str(self.state.source.get("path") or ""))
        return write_textgrids_with_gestures(m, table, directory, [self.signals.gestures])

    def export_gesture_table_dialog(self) -> None:
        from app.export.tables import table_filters
        from app.figures.export import filter_suffixes, suffix_from_filter

        filters = table_filters()
        path, chosen = QtWidgets.QFileDialog.getSaveFileName(self, "Export the gesture table", "gestures.csv", filters)
        if path:
            self._run_export(lambda _p: self.export_gesture_table(suffix_from_filter(path, chosen,
                                                                                     filter_suffixes(filters))),
                             "export the gesture table")

    def export_gesture_textgrids_dialog(self) -> None:
        d = QtWidgets.QFileDialog.getExistingDirectory(self, "Folder for the TextGrids (one per utterance)")
        if d:
            self._run_export(lambda p: self.export_gesture_textgrids(d, p), "export the TextGrids")

    def _run_export(self, task, doing: str) -> None:
        from app.user_messages import plain_errors
        from app.workers import run_task

        run_task(plain_errors(task, doing=doing), parent=self, title=doing.capitalize(),
                 on_done=lambda out: self.say(f"wrote {len(out)} file{'s' * (len(out) != 1)}"),
                 on_error=lambda msg, _tb: self._show_error(msg))

    # ------------------------------------------------------------------ sessions
    def signals_settings(self) -> dict:
        """What a session keeps of the signals (:meth:`app.models.signals.Signals.settings`)."""
        if self.signals is None:
            return dict(self._signals_pending or {})
        return self.signals.settings()

    def apply_signals_settings(self, d: dict) -> None:
        """Restore a session's signals: now when its manifold is shown, else when it is."""
        self._signals_pending = dict(d) if d else None
        if self.state.manifold is not None and d:
            self._signals_on_manifold()

    def landmark_legend(self) -> list:
        """``(code, words, rgb)`` of the landmarks in gesture order (the tier's and the marks' colours)."""
        return [(k, w, landmark_colour(self.state.palette, k)) for k, w in LANDMARK_WORDS.items()]

"""The trajectory editor's timeline, as a phonetician used to Praat drives it (a mixin of the editor).

* A click on the tiers or the sound sets the cursor: the lips show that frame and the
  manifold view selects the state under it (the captured frame of an utterance, the state
  nearest the synthesised trajectory there). A drag selects a stretch of time.
* Tab plays the selection, or the visible part when nothing is selected, and stops at its
  end; Shift+Tab plays from the cursor to the end; either stops what is playing. Space
  plays or pauses anywhere in the editor, and never presses a button.
* Ctrl+I / Ctrl+O zoom in / out (about the cursor), Ctrl+N shows the selection, Ctrl+A all;
  the wheel and + / - zoom too.
* A phone or word boundary dragged is one undoable edit (:mod:`app.models.tier_editing`);
  "Save TextGrid…" writes the edited tiers.

The tiers and the sound under them share one scrolled strip, so they have one width and
one scroll bar; the strip is as tall as what it shows (no room is kept for a sound that is
off or absent).
"""
from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from app.views.editor.commands import TargetsEdit
from app.views.phone_timeline import PhoneTimeline
from app.views.sound_panel import SoundPanel
from app.views.sound_track import SoundTrack

__all__ = ["TimelineControl", "ZOOM_RANGE", "CLICK_PX"]

#: timeline zoom: times the width that shows the whole trajectory
ZOOM_RANGE = (1.0, 64.0)
#: a press and release closer than this (pixels) is a click (sets the cursor), farther a drag (selects)
CLICK_PX = 3


class TimelineControl:
    """Cursor, selection, zoom, Praat's keys and tier edits of :class:`app.views.trajectory_editor.TrajectoryEditor`."""

    # ------------------------------------------------------------------ construction
    def _make_tracks(self, state) -> None:
        self.tracks = QtWidgets.QWidget()
        self.timeline = PhoneTimeline(self.tracks)
        self.timeline.colour = self._palette_colour
        self.sound = SoundPanel(self.tracks)
        self.sound.move(0, self.timeline.tiers_height())
        self.sound.hide()
        self.sound_track = SoundTrack(self.sound, state, parent=self)
        self._make_signals(state)  # the gesture tier and the channels under the sound
        self.sound_box = QtWidgets.QCheckBox("Sound")
        self.sound_box.setChecked(True)
        self.sound_box.setToolTip("Show the utterance's waveform and wide-band spectrogram under the phones "
                                  "(where it has audio)")
        self._press = None  # (frame, x) where the mouse went down on the time axis
        self.scroll = QtWidgets.QScrollArea()
        self.scroll.setWidget(self.tracks)
        self.scroll.setWidgetResizable(False)
        self.scroll.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAsNeeded)
        self.scroll.setVerticalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.scroll.setFocusPolicy(QtCore.Qt.FocusPolicy.NoFocus)
        self.scroll.setMinimumWidth(200)
        self.scroll.viewport().installEventFilter(self)
        for w in (self.timeline, self.sound, *self.signal_rows):
            w.pressed.connect(self._on_time_pressed)
            w.dragged.connect(self._on_time_dragged)
            w.released.connect(self._on_time_released)
            w.keyCommand.connect(self.key_command)
            w.playToggled.connect(self.toggle_playing)
        self.timeline.tiersChanged.connect(self._on_tiers_changed)
        self.sound_box.toggled.connect(lambda _on: self._layout_tracks())
        self.sound_track.changed.connect(lambda _has: self._layout_tracks())
        # Space, Tab and Shift+Tab anywhere in the editor (a text field types its own space)
        self.key_shortcuts = {}
        for keys, slot in (("Space", self.toggle_playing), ("Tab", self.play_selection),
                           ("Shift+Tab", self.play_from_cursor), ("Backtab", self.play_from_cursor)):
            sc = QtGui.QShortcut(QtGui.QKeySequence(keys), self)
            sc.setContext(QtCore.Qt.ShortcutContext.WidgetWithChildrenShortcut)
            sc.activated.connect(slot)
            self.key_shortcuts[keys] = sc

    def _palette_colour(self, kind: str, label: str):
        p = self.state.palette
        return None if p is None else p.colour(kind, label)

    # ------------------------------------------------------------------ layout and zoom
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
        tl.resize(width, tl.tiers_height())
        self.sound.resize(width, self.sound.HEIGHT)
        for row in self.signal_rows:
            row.resize(width, row.height())
        self.tracks.resize(width, self._tracks_height())
        if anchor is not None and tl.targets is not None:
            bar.setValue(int(round(tl._x(anchor[0]) - anchor[1])))
        return self.zoom

    def zoom_by(self, factor: float, anchor_x: float | None = None) -> float:
        if anchor_x is None:
            bar = self.scroll.horizontalScrollBar()
            anchor_x = bar.value() + self.scroll.viewport().width() / 2
        return self.set_zoom(self.zoom * factor, anchor_x)

    def visible_frames(self) -> tuple[float, float]:
        """The first and last frame (fractional) of the timeline shown in the scrolled view."""
        x0 = self.scroll.horizontalScrollBar().value()
        tl = self.timeline
        n = (tl.targets.n_frames - 1) if tl.targets is not None else 0
        a, b = tl.frame_at(x0), tl.frame_at(x0 + self.scroll.viewport().width())
        return max(a, 0.0), min(b, float(n))

    def zoom_to_selection(self) -> bool:
        """Ctrl+N: the selected stretch fills the view (False: nothing selected)."""
        sel, tl = self.timeline.time_selection, self.timeline
        if sel is None or tl.targets is None:
            return False
        a, b = sel
        n = max(tl.targets.n_frames - 1, 1)
        self.set_zoom(n / max(b - a, 1.0) * (1.0 - 2.0 * tl.MARGIN / max(self.scroll.viewport().width(), 1)))
        self.scroll.horizontalScrollBar().setValue(int(round(tl._x(a) - tl.MARGIN)))
        return True

    def _tracks_height(self) -> int:
        h = self.timeline.tiers_height() + (self.sound.HEIGHT if self.sound.isVisibleTo(self.tracks) else 0)
        return h + sum(row.height() for row in self.signal_rows if row.isVisibleTo(self.tracks))

    def strip_cap(self) -> int:
        """The most height the strip shows at once: the tiers, the sound's room and, on a large screen, a gesture
        tier and two channels (taller contents scroll), so the 3-D view keeps its half of the window."""
        cap = self.timeline.tiers_height() + self.sound.HEIGHT
        return cap if getattr(self, "compact", False) else cap + self.gesture_tier.HEIGHT + 2 * self.channels.ROW_H

    def _layout_tracks(self) -> None:
        """Show the sound under the tiers when asked for and the utterance has audio, the gesture tier and the
        channels under it; size the strip to them (at most :meth:`strip_cap` shown, the rest scrolled)."""
        show = self.sound_box.isChecked() and self.sound_track.wanted is not None
        self.sound.setVisible(show)
        self.timeline.resize(self.timeline.width(), self.timeline.tiers_height())
        y = self.timeline.tiers_height()
        self.sound.move(0, y)
        y += self.sound.HEIGHT if show else 0
        for row in self.signal_rows:
            row.move(0, y)
            row.resize(self.timeline.width(), row.height())
            y += row.height() if row.isVisibleTo(self.tracks) else 0
        h = self._tracks_height()
        self.tracks.resize(self.timeline.width(), h)
        shown = min(h, self.strip_cap())
        self.scroll.setVerticalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAsNeeded if shown < h else
                                               QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.scroll.setFixedHeight(shown + self.scroll.horizontalScrollBar().sizeHint().height() + 4)
        self._update_height()

    def needed_height(self) -> int:
        """The height the editor's contents need at its width (its controls wrap into rows)."""
        lay = self.layout()
        if lay is None:
            return self.sizeHint().height()
        return lay.totalHeightForWidth(max(self.width(), 1)) if lay.hasHeightForWidth() else \
            lay.totalSizeHint().height()

    def _update_height(self) -> None:
        """Keep the editor exactly as tall as it needs: its minimum (nothing clipped), and the dock's height
        (no room kept for a sound that is off or absent, nor for controls that fit fewer rows)."""
        need = self.needed_height()
        if need != self.minimumHeight():
            self.setMinimumHeight(need)
        if need != getattr(self, "_wanted", None):
            self._wanted = need
            self.heightWanted.emit(need)

    def resizeEvent(self, ev):
        super().resizeEvent(ev)
        self._update_height()

    def set_compact(self, on: bool) -> None:
        """Lower tiers and sound, for a small screen (the window decides from its height)."""
        if getattr(self, "compact", None) == bool(on):
            return
        self.compact = bool(on)
        self.timeline.set_compact(on)
        self.sound.set_compact(on)
        for row in self.signal_rows:
            row.set_compact(on)
        self.set_zoom(self.zoom)
        self._layout_tracks()

    def eventFilter(self, obj, ev):
        if obj is self.scroll.viewport() and ev.type() == QtCore.QEvent.Type.Resize:
            self.set_zoom(self.zoom)
        return super().eventFilter(obj, ev)

    # ------------------------------------------------------------------ cursor and selection
    def _set_cursor(self, frame) -> None:
        """Where playback is (the state's playback frame), drawn as the cursor."""
        if frame is None:
            return
        for w in (self.timeline, self.sound, *self.signal_rows):
            w.set_cursor(frame)

    def set_time_selection(self, span) -> None:
        """The selected stretch ``(first, last)`` frame on the tiers, the sound and the rows under it (None: none)."""
        for w in (self.timeline, self.sound, *self.signal_rows):
            w.set_time_selection(span)

    def _on_time_pressed(self, frame, x) -> None:
        self._press = (float(frame), float(x))

    def _on_time_dragged(self, frame, x) -> None:
        if self._press is not None and abs(x - self._press[1]) > CLICK_PX:
            n = self.timeline.targets.n_frames - 1
            a, b = sorted((self._press[0], float(frame)))
            self.set_time_selection((max(a, 0.0), min(b, float(n))))

    def _on_time_released(self, frame, x) -> None:
        press, self._press = self._press, None
        if press is not None and abs(x - press[1]) <= CLICK_PX:
            self.set_time_selection(None)  # a click clears the selection and sets the cursor
            self.set_cursor_frame(press[0])

    def set_cursor_frame(self, frame) -> None:
        """Put the cursor at ``frame``: the lips show it, and the manifold view selects the state under it."""
        tl = self.timeline
        if tl.targets is None:
            return
        k = int(min(max(round(float(frame)), 0), tl.targets.n_frames - 1))
        for w in (tl, self.sound, *self.signal_rows):
            w.set_cursor(k)
        s = self.state
        with s.batch():  # one action: every view redraws once
            if s.n_playback:
                s.set_playing(False)
                s.set_playback(min(k, s.n_playback - 1))
            self._select_under(k)

    def _select_under(self, k: int) -> None:
        """Select, in the manifold view, the state of frame ``k`` of what the timeline shows."""
        s = self.state
        orig, syn = s.original, s.synthetic
        if orig is not None and orig.frames is not None and len(orig.frames):
            s.select_frame(int(orig.frames[min(k, len(orig.frames) - 1)]), as_target=False)
        elif syn is not None and len(syn):
            C = np.asarray(s.manifold.states_.centroids_)
            y = np.asarray(syn.Y)[min(k, len(syn) - 1)]
            d = min(C.shape[1], y.shape[0])
            s.select_state(int(np.argmin(np.linalg.norm(C[:, :d] - y[:d], axis=1))))

    # ------------------------------------------------------------------ Praat's keys
    def key_command(self, name: str) -> None:
        """A Praat key from the tiers or the sound (:data:`app.views.phone_timeline.KEY_COMMANDS`)."""
        tl = self.timeline
        centre = (tl._x(tl.cursor) if tl.cursor is not None and tl.targets is not None else None)
        {"play": self.play_selection, "play-from-cursor": self.play_from_cursor,
         "zoom-in": lambda: self.zoom_by(2.0, centre), "zoom-out": lambda: self.zoom_by(0.5, centre),
         "zoom-selection": self.zoom_to_selection, "zoom-all": lambda: self.set_zoom(1.0),
         "clear-selection": lambda: self.set_time_selection(None)}[name]()

    def _nothing_to_play(self) -> bool:
        if self.state.n_playback:
            return False
        self.say("nothing to play yet: press Synthesise, or choose an utterance")
        return True

    def play_selection(self) -> bool:
        """Tab: play the selection, or the visible part, and stop; stop what plays."""
        s = self.state
        if s.playing:
            s.set_playing(False)
            return False
        if self._nothing_to_play() or self.timeline.targets is None:
            return False
        a, b = self.timeline.time_selection or self.visible_frames()
        return s.play(int(np.floor(a)), int(np.ceil(b)) + 1)

    def play_from_cursor(self) -> bool:
        """Shift+Tab: play from the cursor to the end; stop what plays."""
        s = self.state
        if s.playing:
            s.set_playing(False)
            return False
        if self._nothing_to_play():
            return False
        return s.play(int(self.timeline.cursor or 0))

    def toggle_playing(self) -> None:
        """Space: play or pause (through the state, as the Play buttons do)."""
        self.state.set_playing(not self.state.playing)

    def step(self, delta: int) -> None:
        """Left / Right in the timeline: pause and show the previous / next frame."""
        s = self.state
        if s.n_playback == 0:
            return
        s.set_playing(False)
        k = 0 if s.playback is None else s.playback + int(delta)
        s.set_playback(min(max(k, 0), s.n_playback - 1))

    # ------------------------------------------------------------------ tiers
    def _on_tiers_changed(self, before, after, words_before, words_after, text) -> None:
        self.undo_stack.push(TargetsEdit(self, before, after, text, tuple(words_before), tuple(words_after)))

    def save_textgrid(self, path):
        """Write the tiers as they are now (phones, words where there are, the targets) as a TextGrid."""
        from app.models.tier_editing import write_tiers_textgrid

        if self.targets is None:
            raise ValueError("no tiers to save: load targets first")
        return write_tiers_textgrid(path, self.targets, self.words)

    def save_textgrid_dialog(self) -> None:
        from pathlib import Path

        from app.user_messages import user_message

        if self.targets is None:
            self._show_error("no tiers to save: load targets first")
            return
        stem = self.targets.utterance or "tiers"
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Save the tiers as a TextGrid", f"{stem}.TextGrid",
                                                        "Praat TextGrid (*.TextGrid)")
        if not path:
            return
        if not path.lower().endswith(".textgrid"):
            path += ".TextGrid"
        try:
            out = self.save_textgrid(path)
        except (OSError, ValueError) as exc:
            self._show_error(user_message(exc, doing="save the TextGrid", path=path))
            return
        self.say(f"wrote {Path(out).name}: the tiers as edited")

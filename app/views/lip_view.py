"""The lip view: the lips of the selected frame or state, component deformations and playback.

* A selected frame shows its captured geometry; a selected state (no frame) shows
  its centroid mapped back through the inverse map (Y -> F^x -> F).
* A shape component chosen in the scree panel shows the mean shape -2 s.d. (left)
  and +2 s.d. (right).
* Playback shows the original trajectory (left, grey-pink) and the synthetic one
  (right, red) side by side, at the corpus rate, with the utterance's audio when it
  has any and a sound device exists. The frame shown comes from elapsed time
  (:class:`app.models.playback.PlaybackClock`: the audio device's position while the sound
  plays, the monotonic clock otherwise), not from counting timer ticks: when a frame
  takes longer to draw than the frame period, the frames in between are dropped and
  playback stays in step with the clock. A single-shot timer fires at the moment the
  next frame becomes due (on screen after the measured display latency).
* The 3-D widget is a native window of its own, so a playback frame repaints only it:
  in a window whose widgets are all composed by Qt, every frame made Qt compose the
  whole 1400×900 window through (software) OpenGL, which cost more than the frame. The
  caption and slider follow playback at most every ``READOUT_INTERVAL_S`` (each of their
  repaints composes the whole window); the manifold view follows at a lower rate, see
  ``ManifoldView``.
"""
from __future__ import annotations

import math
import time

import numpy as np
from PySide6 import QtCore, QtWidgets

from app import scene
from app.audio import AudioPlayer
from app.models.playback import PlaybackClock
from app.models.trajectories import lip_frames
from app.views._common import (
    READOUT_INTERVAL_S,
    RenderScheduler,
    Throttle,
    camera_of,
    close_plotter,
    connect_all,
    disconnect_all,
    drawing_frame,
    make_plotter,
    set_camera,
)

__all__ = ["LipView", "READOUT_INTERVAL_S"]

MAIN_COLOUR = (0.86, 0.55, 0.55)
SYNTH_COLOUR = (0.95, 0.15, 0.1)
SPEEDS = (("1×", 1.0), ("½×", 0.5), ("¼×", 0.25))


class LipView(QtWidgets.QWidget):
    """Lip mesh (or markers) bound to an :class:`app.models.state.AppState`."""

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.state = state
        self.main = self.second = None
        self._frames = {"original": None, "synthetic": None}
        self.audio = AudioPlayer(self)
        self.clock = None  # a PlaybackClock while playing
        self.clock_source = time.monotonic  # seconds; the audio clock's time base (tests pass a fake)
        # the audio device's position in media seconds while sound plays, else None (tests pass a fake)
        self.position_source = self.audio.position_s
        self.shown_frame = None  # the playback frame the lip meshes hold (None outside playback)
        self._chosen_at = None
        # display latencies the last playback measured (and the clock source they were measured on):
        # the next playback looks ahead by them from its first frame (the first one in a window by
        # one frame drawn at Play)
        self._latencies = ((), None)
        self.timer = QtCore.QTimer(self)
        self.timer.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        self.timer.setSingleShot(True)  # each tick sets the next deadline; a late tick is never queued
        self.timer.timeout.connect(self._tick)

        self.play_btn = QtWidgets.QPushButton("Play")
        self.play_btn.setCheckable(True)
        self.play_btn.setToolTip("Play the original and synthetic trajectories side by side")
        self.stop_btn = QtWidgets.QPushButton("Stop")
        self.speed_box = QtWidgets.QComboBox()
        for label, v in SPEEDS:
            self.speed_box.addItem(label, v)
        self.slider = QtWidgets.QSlider(QtCore.Qt.Orientation.Horizontal)
        self.slider.setEnabled(False)
        self.caption = QtWidgets.QLabel("")
        self.caption.setWordWrap(True)
        self.caption.setAlignment(QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.AlignmentFlag.AlignTop)
        # two lines, whatever the text: a caption that re-wraps to another height would resize the
        # 3-D widget during playback (a VTK resize, and the window composed whole from then on)
        self.caption.setFixedHeight(2 * self.caption.fontMetrics().lineSpacing() + 4)
        self._caption_readout = Throttle(self.caption.setText, READOUT_INTERVAL_S, parent=self)
        self._slider_readout = Throttle(self._set_slider, READOUT_INTERVAL_S, parent=self)
        bar = QtWidgets.QHBoxLayout()
        bar.setContentsMargins(4, 2, 4, 2)
        for w in (self.play_btn, self.stop_btn, self.speed_box):
            bar.addWidget(w)
        bar.addWidget(self.slider, 1)
        self.plotter = make_plotter(self)
        self.renderer = RenderScheduler(self.plotter)
        self.plotter.interactor.frameSwapped.connect(self._on_swapped)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addWidget(self.plotter.interactor, 1)
        lay.addLayout(bar)
        lay.addWidget(self.caption)

        self.play_btn.toggled.connect(state.set_playing)
        self.stop_btn.clicked.connect(self._stop)
        self.slider.valueChanged.connect(self._on_slider)
        self.speed_box.currentIndexChanged.connect(lambda _i: self._restart_clock())
        self._connections = [(state.events.changed, self._on_changed)]
        connect_all(self._connections)
        if state.manifold is not None:
            self.rebuild()

    # ------------------------------------------------------------------ build
    def rebuild(self) -> None:
        p = self.plotter
        p.clear_actors()
        self.main = self.second = None
        m = self.state.manifold
        if m is None:
            self.renderer.request()
            return
        c = m.corpus_
        from app.models.lip_drawing import lip_drawing
        from engine.recordings.orientation import anatomical_frame

        # points drawn in the talker's frame, seen from the front
        self.orientation = anatomical_frame(c, m.shape_.mean_)
        mean = self._points(m.shape_.mean_)
        # what is drawn: a measured surface as a surface, sensors as sensors (app.models.lip_drawing, as the figures)
        self.drawing = lip_drawing(c, mean, frame=self.orientation)
        ext = mean.max(0) - mean.min(0)
        # side by side, with room between them for the sensors' labels (a profile is narrow: its own height)
        room = 1.25 if self.drawing.kind == "surface" else 1.6
        self.offset = np.array([room * max(float(ext[0]), float(ext[1]) if self.drawing.view == "profile" else 0.0,
                                           1e-6), 0.0, 0.0])
        self.main = scene.add_lips(p, mean, c.faces, color=MAIN_COLOUR, name="lips_main", names=c.point_names,
                                   drawing=self.drawing)
        self.second = scene.add_lips(p, mean, c.faces, color=SYNTH_COLOUR, offset=self.offset, name="lips_second",
                                     names=c.point_names, drawing=self.drawing, labels=False)
        self.second.set_visible(False)
        self._on_trajectories(render=False)
        # the lips face the viewer: the talker's frame puts forward on +z, up on +y, the talker's left on +x
        p.view_xy(render=False)
        self._frame_camera()
        p.camera_set = True
        self.refresh()

    def reset_camera(self) -> None:
        """Look at the lips from the front again, framed as when they were first drawn."""
        if self.main is None:
            return
        self.plotter.view_xy(render=False)
        self._frame_camera()
        self.renderer.request()

    def _frame_camera(self) -> None:
        """Frame the lips shown (one or both) with room for what stands beside the sensors: their labels,
        the aperture's value, a profile's face direction."""
        handles = [h for h in (self.main, self.second) if h is not None and h.visible]
        if not handles:
            self.plotter.renderer.reset_camera(render=False)
            return
        P = np.concatenate([np.asarray(h.points, np.float64) + np.asarray(h.offset, np.float64) for h in handles])
        lo, hi = P.min(axis=0), P.max(axis=0)
        ext = float(np.ptp(P[:, :2], axis=0).max()) or 1.0
        pad = (0.12 if self.drawing.kind == "surface" else 0.55) * ext
        # the renderer's, not the plotter's: pyvista's Plotter.reset_camera renders whatever ``render`` says
        self.plotter.renderer.reset_camera(render=False, bounds=[lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad,
                                                                 lo[2], hi[2]])

    def _points(self, row) -> np.ndarray:
        """One frame row (C,) as points (V, 3) in the talker's view coordinates (engine.recordings.orientation)."""
        from engine.recordings.corpus import frame_points

        row = self.orientation.view_frames(np.asarray(row, np.float32)[None])[0]
        return frame_points(row, self.state.manifold.corpus_.dims)

    # ---------------------------------------------------------------- refresh
    def _on_changed(self, names) -> None:
        """One action's changed fields (``events.changed``): at most one refresh and one render."""
        if "manifold" in names:
            self.rebuild()
            return
        if "trajectory" in names:
            self._on_trajectories(render=False)
        if names & {"frame", "state", "component", "playback", "trajectory"}:
            self.refresh()
        if "playing" in names:
            self._on_playing(self.state.playing)

    def refresh(self, render=True) -> None:
        """Show what the state selects (playback > component > frame > state > mean)."""
        s, m = self.state, self.state.manifold
        if m is None or self.main is None:
            return
        second, second_colour, slider = None, SYNTH_COLOUR, None
        self.shown_frame = None
        if s.playback is not None and (self._frames["original"] is not None or self._frames["synthetic"] is not None):
            k = s.playback
            fo, fs = self._frames["original"], self._frames["synthetic"]
            main = fo[min(k, len(fo) - 1)] if fo is not None else fs[min(k, len(fs) - 1)]
            if fo is not None and fs is not None:
                second = fs[min(k, len(fs) - 1)]
            t = k / (s.original or s.synthetic).rate
            text = f"playback frame {k + 1}/{s.n_playback} ({t:.2f} s)"
            if second is not None:
                text += ": original (left), " + (s.synthetic.label or "synthetic") + " (right, red)"
            slider = k
            self.shown_frame = k
        elif s.component is not None:
            i = s.component
            main = m.shape_.component_deformation(i, -2.0)
            second = m.shape_.component_deformation(i, 2.0)
            second_colour = MAIN_COLOUR
            text = f"shape component {i + 1}: mean −2 s.d. (left), +2 s.d. (right)"
        elif s.frame is not None:
            main = m.corpus_.frames[s.frame]
            text = f"frame {s.frame} (captured)"
        elif s.state is not None:
            Fx = m.inverse_map.transform(m.states_.centroids_[[s.state]][:, :m.inverse_map.n_dims])
            main = m.shape_.inverse_transform(Fx)[0]
            text = f"state {s.state} (centroid through the inverse map)"
        else:
            main = m.shape_.mean_
            text = "mean shape"
        self.main.update(self._points(main))
        if second is not None:
            self.second.update(self._points(second))
            self.second.set_colour(second_colour)
        if self.second.visible != (second is not None):  # frame one mesh or both, once per change
            self.second.set_visible(second is not None)
            self._frame_camera()
        self.caption.setToolTip(f"{text}\n{self.drawing.note}")  # the whole text where two lines are too few
        if s.playing:  # readouts at a few per second: each of their repaints composes the window
            self._caption_readout(text)
            if slider is not None:
                self._slider_readout(slider)
        else:
            self._caption_readout.cancel()
            self._slider_readout.cancel()
            self.caption.setText(text)
            if slider is not None:
                self._set_slider(slider)
        if render:
            self.renderer.request()

    def _set_slider(self, k) -> None:
        self.slider.blockSignals(True)
        self.slider.setValue(k)
        self.slider.blockSignals(False)

    def _on_trajectories(self, render=True):
        m = self.state.manifold
        self._frames = {k: (None if getattr(self.state, k) is None else lip_frames(m, getattr(self.state, k)))
                        for k in ("original", "synthetic")}
        n = self.state.n_playback
        self.slider.blockSignals(True)
        self.slider.setRange(0, max(n - 1, 0))
        self.slider.setValue(0)
        self.slider.setEnabled(n > 0)
        self.slider.blockSignals(False)
        self.play_btn.setEnabled(n > 0)
        if render:
            self.refresh()

    # --------------------------------------------------------------- playback
    @property
    def speed(self) -> float:
        return float(self.speed_box.currentData())

    def _on_playing(self, on: bool) -> None:
        self.play_btn.blockSignals(True)
        self.play_btn.setChecked(on)
        self.play_btn.setText("Pause" if on else "Play")
        self.play_btn.blockSignals(False)
        s = self.state
        if on:
            if s.playback is None or s.playback >= s.n_playback - 1:
                s.set_playback(0)
            self._restart_clock()
            self._start_audio()
        else:
            self.timer.stop()
            if self.clock is not None:
                self._latencies = (self.clock.latencies, self.clock.clock)
            self.clock = None
            self.audio.stop()
            self._caption_readout.flush()  # paused: the readouts show where it stopped, now
            self._slider_readout.flush()

    def _restart_clock(self) -> None:
        """(Re)start the playback clock at the shown frame (on play, or when the speed changes)."""
        s = self.state
        if not s.playing:
            return
        rate = (s.original or s.synthetic).rate
        c = self.clock
        if (c is not None and c.rate == rate and c.n_frames == s.n_playback and c.clock is self.clock_source
                and c.position is self.position_source):
            c.speed = self.speed  # a new speed: keep what was measured of the display latency
            self.audio.set_rate(self.speed)  # the clock takes the sound's position again once it moves
        else:
            seen, source = self._latencies
            if source is not self.clock_source:  # nothing measured on this clock: measure one frame now
                seen = (self._measure_latency(),)
            self.clock = PlaybackClock(rate, s.n_playback, speed=self.speed, clock=self.clock_source,
                                       position=self.position_source, latencies=seen)
        self.clock.start(s.playback or 0)
        self.timer.start(0)

    def _measure_latency(self) -> float:
        """Seconds to draw the shown frame and put it on screen now: the first look-ahead of a playback."""
        t = self.clock_source()
        self.renderer.request()
        self.renderer.flush(sync=True)
        return max(0.0, self.clock_source() - t)

    def _start_audio(self):
        from app.files.sound import playback_audio

        found = playback_audio(self.state)  # the utterance's sound, or the synthesised text spoken
        if found is not None:
            path, rate = found
            self.audio.play(path, start_s=(self.state.playback or 0) / rate, rate=self.speed)

    def _tick(self):
        """Show the frame due now (dropping those whose time has passed), then wait for the next one.

        The frame is the one due when it will reach the screen: the clock looks ahead by
        the latency measured from choosing a frame to its ``frameSwapped``. It is painted
        at once, alone: the readouts it changes repaint just after its
        swap (:func:`app.views._common.drawing_frame`), so nothing else's painting sits
        between a frame's choice and its arrival on screen. The timer is single-shot, set
        to the moment the next frame becomes the one to choose.
        """
        s, clock = self.state, self.clock
        if clock is None or not s.playing:
            return
        k = clock.frame()
        if k is None:  # the clock is past the end: show the last frame and stop
            with s.batch():
                s.set_playback(s.n_playback - 1)
                s.set_playing(False)
            return
        if k != s.playback:
            self._chosen_at = clock.clock()
            with drawing_frame():  # the readouts wait until the frame is on screen
                s.set_playback(k)
                # paint this widget (a native window: it alone) now, nothing else in between
                self.renderer.flush(sync=True)
        self.timer.start(max(1, math.ceil(1000.0 * clock.next_tick_in(k))))

    def _on_swapped(self) -> None:
        """A frame reached the screen: feed the latency it took to the clock's look-ahead."""
        if self.clock is not None and self._chosen_at is not None:
            self.clock.shown(self._chosen_at, self.clock.clock())
            self._chosen_at = None

    def _stop(self):
        with self.state.batch():  # one action: one redraw
            self.state.set_playing(False)
            self.state.set_playback(None)

    def _on_slider(self, v):
        if self.state.n_playback:
            with self.state.batch():
                self.state.set_playing(False)
                self.state.set_playback(int(v))

    # ---------------------------------------------------------------- misc
    def camera(self) -> list:
        return camera_of(self.plotter)

    def set_camera(self, cam) -> None:
        set_camera(self.plotter, cam)

    def close_view(self) -> None:
        self.timer.stop()
        self._caption_readout.cancel()
        self._slider_readout.cancel()
        self.clock = None
        self.audio.stop()
        disconnect_all(self._connections)
        self.renderer.stop()
        close_plotter(self.plotter)

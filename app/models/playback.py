"""Playback timing: which frame to show now, and when to choose the next one (Qt-free).

Playback is driven by a clock, never by counting timer ticks: a tick that comes late
(a slow render, a busy machine) skips the frames whose time has passed instead of
falling behind. The clock is the *media time* of the utterance (seconds from its first
frame; frame ``k`` is due at ``k / rate``):

* when the utterance's audio plays, media time follows the audio device's position
  (``position()``), which moves in coarse steps: between steps it runs on the monotonic
  clock at the playback speed, and every new position pulls it in (a small error is
  slewed out gradually, a large one — a seek, a stall of the audio — is taken at once);
* without audio (no sound file, no device) it is the monotonic clock since Play,
  times the speed.

:class:`PlaybackClock` chooses the frame for the moment it will be *on screen* — the
clock now plus the measured display latency (present-time prediction) — and says when
the next frame becomes the right one (:meth:`PlaybackClock.next_tick_in`), so a timer
can fire at that deadline instead of polling.
"""
from __future__ import annotations

import math
import time
from collections import deque

__all__ = ["playback_frame", "PlaybackClock"]


def playback_frame(elapsed_s: float, rate: float, *, start: int = 0, speed: float = 1.0) -> int:
    """The frame due ``elapsed_s`` seconds after playback started at frame ``start``.

    Parameters
    ----------
    elapsed_s : float
        Seconds since playback started (negative counts as 0).
    rate : float
        Frames per second of the trajectory (the corpus rate), > 0.
    start : int
        Frame shown at ``elapsed_s == 0``.
    speed : float
        Playback speed (1 = real time, 0.5 = half speed), > 0.

    Returns
    -------
    int
        ``start + floor(elapsed_s * rate * speed)``; may exceed the last frame (the
        caller stops there).
    """
    if not (rate > 0 and math.isfinite(rate)):
        raise ValueError(f"rate must be a positive number of frames per second, got {rate!r}")
    if not (speed > 0 and math.isfinite(speed)):
        raise ValueError(f"speed must be a positive factor (1 = real time), got {speed!r}")
    elapsed_s = max(0.0, float(elapsed_s))
    # a hair of tolerance so that k / rate seconds shows frame k despite rounding
    return int(start) + int(math.floor(elapsed_s * rate * speed + 1e-9))


class PlaybackClock:
    """Media time of a playing utterance, and the frame to show for it.

    Parameters
    ----------
    rate : float
        Frames per second (> 0).
    n_frames : int
        Frames in the trajectory; :meth:`frame` returns None past the last one.
    speed : float, default=1.0
        Media seconds per second of the monotonic clock (the audio's playback rate).
    clock : callable() -> float, default=time.monotonic
        Seconds; tests pass a fake clock.
    position : callable() -> float or None, optional
        The audio device's position in media seconds (what is being heard now), or None
        while it has none (no audio, not started). None: the monotonic clock alone.
    latency_window : int, default=15
        The look-ahead is the second-largest latency of this many latest frames (about
        their 90th percentile: one stall does not make the following frames run early,
        and the frames' common delays, preemption by other processes included, are
        covered more often than by the upper quartile).
    resync_s : float, default=0.1
        An audio position further than this from the clock's media time is taken at once
        (a seek or a stall); a nearer one is slewed in.
    slew : float, default=0.2
        Fraction of a small audio-position error corrected at each new position (0 < slew <= 1).
    latencies : iterable of float, default=()
        Display latencies (s) measured before, e.g. by the previous playback's clock
        (:attr:`latencies`): the first frames look ahead by them instead of by nothing.
    lead_s : float, default=0.015
        How far ahead of the sound the picture aims to be, at the typical (median) latency:
        the look-ahead is at least the median latency plus this. 15 ms puts the typical
        error, over the time a frame is on screen, near the centre of the broadcast
        lip-sync window (ATSC IS-191: sound at most 15 ms before the picture, at most
        45 ms after it), so a frame delayed by a stall has 15 ms more before it trails
        the sound. 0 to aim at the median latency itself.

    Attributes
    ----------
    latency_s : float
        Estimated time from choosing a frame to its being on screen: the second-largest
        latency of the window (0 until one is measured).
    look_ahead_s : float
        How far ahead of the clock a frame is chosen: ``latency_s``, or the median
        latency plus ``lead_s`` when that is larger (0 until a latency is measured).
    following_audio : bool
        True once the audio position has moved since :meth:`start`: the clock follows it
        from then on (taking that first moved position at once, so the audio's start-up
        delay is not the video's).
    n_resyncs : int
        Audio positions taken at once (errors beyond ``resync_s``) since :meth:`start`.
    """

    def __init__(self, rate: float, n_frames: int, *, speed: float = 1.0, clock=time.monotonic, position=None,
                 latency_window: int = 15, resync_s: float = 0.1, slew: float = 0.2, latencies=(),
                 lead_s: float = 0.015):
        playback_frame(0.0, rate, speed=speed)  # validates rate and speed
        if int(n_frames) < 1:
            raise ValueError(f"n_frames must be >= 1 (a trajectory to play), got {n_frames!r}")
        if int(latency_window) < 1:
            raise ValueError(f"latency_window must be >= 1 frame, got {latency_window!r}")
        if not (resync_s > 0 and math.isfinite(resync_s)):
            raise ValueError(f"resync_s must be a positive number of seconds, got {resync_s!r}")
        if not 0 < slew <= 1:
            raise ValueError(f"slew must be in (0, 1] (the fraction of an error corrected per position), got {slew!r}")
        if not (math.isfinite(lead_s) and 0 <= lead_s <= 0.1):
            raise ValueError(f"lead_s must be 0-0.1 s (how far the picture aims ahead of the sound), got {lead_s!r}")
        self.rate = float(rate)
        self.n_frames = int(n_frames)
        self.speed = float(speed)
        self.clock = clock
        self.position = position
        self.resync_s = float(resync_s)
        self.slew = float(slew)
        self.lead_s = float(lead_s)
        self.latency_s = 0.0
        self.look_ahead_s = 0.0
        self._latencies = deque(maxlen=int(latency_window))
        for v in latencies:
            self._record_latency(v)
        self.start_frame = 0
        self.t0 = None
        self._anchor = (0.0, 0.0)  # (clock time, media time) the clock runs on from
        self._last_position = None
        self.following_audio = False
        self.n_resyncs = 0
        self._latest = -1  # the latest frame chosen since the last start or re-sync

    def start(self, frame: int = 0) -> None:
        """Start (or restart) playback at ``frame`` now (media time ``frame / rate``)."""
        if not 0 <= int(frame) < self.n_frames:
            raise IndexError(f"start frame {frame} out of range 0..{self.n_frames - 1}")
        self.start_frame = int(frame)
        self.t0 = self.clock()
        self._anchor = (self.t0, self.start_frame / self.rate)
        self._last_position = self._read_position()  # a position left from before Play is not news
        self.following_audio = False
        self.n_resyncs = 0
        self._latest = -1

    @property
    def running(self) -> bool:
        return self.t0 is not None

    def _check_started(self):
        if self.t0 is None:
            raise RuntimeError("the playback clock has not been started")

    def _read_position(self):
        if self.position is None:
            return None
        p = self.position()
        return None if p is None or not math.isfinite(p) else float(p)

    def elapsed(self) -> float:
        """Seconds of the monotonic clock since :meth:`start`."""
        self._check_started()
        return self.clock() - self.t0

    def sync(self) -> None:
        """Take in the audio position if it moved since the last call (cheap; :meth:`frame` calls it)."""
        self._check_started()
        p = self._read_position()
        if p is None:
            return
        last, self._last_position = self._last_position, p
        if last is None or p == last:  # news is a position that moved
            return
        now = self.clock()
        err = p - self.media_time(now)
        if not self.following_audio or abs(err) > self.resync_s:
            # the audio has just started moving (its start-up delay is not the video's), or jumped
            self.n_resyncs += self.following_audio
            self.following_audio = True
            self._anchor = (now, p)
            self._latest = -1  # a real jump may go back; small corrections may not
        else:
            t, m = self._anchor
            self._anchor = (t, m + self.slew * err)

    def media_time(self, at: float | None = None) -> float:
        """Media seconds at clock time ``at`` (default now), as the clock last synced."""
        self._check_started()
        t = self.clock() if at is None else float(at)
        t_a, m_a = self._anchor
        return m_a + (t - t_a) * self.speed

    def due(self, at: float | None = None) -> int:
        """The frame whose time has come at clock time ``at`` (default now), without look-ahead; may be past the end."""
        return int(math.floor(self.media_time(at) * self.rate + 1e-9))

    def frame(self) -> int | None:
        """The frame nearest the clock when the one rendered now reaches the screen; None at the end.

        Syncs to the audio first. Nearest rather than the one already begun, and the
        look-ahead (:attr:`look_ahead_s`) the larger of the latency near its top
        (second-largest of the window) and the median latency plus ``lead_s``: a frame
        then errs towards being early rather than late (sight ahead of sound is tolerated
        far better than behind it). Between a start (or an audio re-sync jump) and the end the
        chosen frames never decrease: when the look-ahead shrinks the latest one is held.
        """
        self.sync()
        now = self.clock()
        if self.due(now) >= self.n_frames:
            return None
        k = int(math.floor(self.media_time(now + self.look_ahead_s) * self.rate + 0.5))
        # a shorter look-ahead or a small audio correction must not step the picture back:
        # hold the latest frame instead (only start() or a re-sync jump may go back)
        k = min(max(k, 0, self._latest), self.n_frames - 1)
        self._latest = k
        return k

    def next_tick_in(self, shown: int | None) -> float:
        """Clock seconds until a frame other than ``shown`` becomes the one to choose.

        That is when the predicted on-screen media time passes ``shown + 0.5`` frames (the
        moment :meth:`frame` turns to ``shown + 1``); 0 when that moment has passed. Never
        more than one frame period of clock time, so a tick still comes if the audio
        position jumps.
        """
        self._check_started()
        period = 1.0 / (self.rate * self.speed)
        if shown is None:
            return 0.0
        now = self.clock()
        frames_left = (int(shown) + 0.5) - self.media_time(now + self.look_ahead_s) * self.rate
        return min(max(0.0, frames_left / (self.rate * self.speed)), period)

    def lag_frames(self, frame: int, at: float | None = None) -> float:
        """How many frame periods ``frame`` is behind the media time at ``at`` (negative: early)."""
        return self.media_time(at) * self.rate - int(frame)

    @property
    def latencies(self) -> tuple:
        """The display latencies (s) the look-ahead is taken from, oldest first (to seed another clock)."""
        return tuple(self._latencies)

    def shown(self, chosen_at: float, shown_at: float) -> None:
        """Record that a frame chosen at ``chosen_at`` reached the screen at ``shown_at``."""
        self._record_latency(float(shown_at) - float(chosen_at))

    def _record_latency(self, seconds: float) -> None:
        if not math.isfinite(seconds):
            raise ValueError(f"a display latency must be a finite number of seconds, got {seconds!r}")
        # never plan for more than a quarter second ahead
        self._latencies.append(min(max(0.0, float(seconds)), 0.25))
        ordered = sorted(self._latencies)
        self.latency_s = ordered[max(0, len(ordered) - 2)]  # the second-largest
        self.look_ahead_s = max(self.latency_s, ordered[len(ordered) // 2] + self.lead_s)

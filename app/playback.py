"""Playback timing: which frame to show now, from elapsed time (Qt-free).

Playback is driven by a clock, never by counting timer ticks: a tick that comes late
(a slow render, a busy machine) skips the frames whose time has passed instead of
falling behind, so the shown frame keeps up with the audio. :class:`PlaybackClock`
also looks ahead by the measured display latency (how long a frame takes from being
chosen to being on screen), so the frame that reaches the screen is the one due at
that moment.
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
    """Maps a clock to the frame to show, with look-ahead for display latency.

    Parameters
    ----------
    rate : float
        Frames per second (> 0).
    n_frames : int
        Frames in the trajectory; :meth:`frame` returns None past the last one.
    speed : float, default=1.0
    clock : callable() -> float, default=time.monotonic
        Seconds; tests pass a fake clock.
    latency_window : int, default=15
        The look-ahead is the upper quartile of the latency of this many latest frames (a
        quantile, so that one stall does not make the following frames run early).

    Attributes
    ----------
    latency_s : float
        Estimated time from choosing a frame to its being on screen.
    """

    def __init__(self, rate: float, n_frames: int, *, speed: float = 1.0, clock=time.monotonic,
                 latency_window: int = 15):
        playback_frame(0.0, rate, speed=speed)  # validates rate and speed
        if int(n_frames) < 1:
            raise ValueError(f"n_frames must be >= 1 (a trajectory to play), got {n_frames!r}")
        if int(latency_window) < 1:
            raise ValueError(f"latency_window must be >= 1 frame, got {latency_window!r}")
        self.rate = float(rate)
        self.n_frames = int(n_frames)
        self.speed = float(speed)
        self.clock = clock
        self.latency_s = 0.0
        self._latencies = deque(maxlen=int(latency_window))
        self.start_frame = 0
        self.t0 = None

    def start(self, frame: int = 0) -> None:
        """Start (or restart) playback at ``frame`` now."""
        if not 0 <= int(frame) < self.n_frames:
            raise IndexError(f"start frame {frame} out of range 0..{self.n_frames - 1}")
        self.start_frame = int(frame)
        self.t0 = self.clock()

    @property
    def running(self) -> bool:
        return self.t0 is not None

    def elapsed(self) -> float:
        """Seconds since :meth:`start`."""
        if self.t0 is None:
            raise RuntimeError("the playback clock has not been started")
        return self.clock() - self.t0

    def due(self, at: float | None = None) -> int:
        """The frame due at clock time ``at`` (default now), without look-ahead; may be past the end."""
        if self.t0 is None:
            raise RuntimeError("the playback clock has not been started")
        t = self.clock() if at is None else float(at)
        return playback_frame(t - self.t0, self.rate, start=self.start_frame, speed=self.speed)

    def frame(self) -> int | None:
        """The frame nearest the clock when the one rendered now reaches the screen; None at the end.

        Nearest rather than the one already begun, and the latency taken at its upper
        quartile: a frame then errs towards being early by less than a frame period rather
        than late (sight ahead of sound is tolerated far better than behind it).
        """
        if self.t0 is None:
            raise RuntimeError("the playback clock has not been started")
        if self.due() >= self.n_frames:
            return None
        half = 0.5 / (self.rate * self.speed)
        return min(self.due(self.clock() + self.latency_s + half), self.n_frames - 1)

    def shown(self, chosen_at: float, shown_at: float) -> None:
        """Record that a frame chosen at ``chosen_at`` reached the screen at ``shown_at``."""
        # never plan for more than a quarter second ahead
        self._latencies.append(min(max(0.0, float(shown_at) - float(chosen_at)), 0.25))
        ordered = sorted(self._latencies)
        self.latency_s = ordered[int(round(0.75 * (len(ordered) - 1)))]  # the upper quartile

"""Playback timing from elapsed time (app.playback): pure functions with a fake clock, no display."""
from __future__ import annotations

import pytest

from app.playback import PlaybackClock, playback_frame


class FakeClock:
    def __init__(self, t=100.0):
        self.t = t

    def __call__(self):
        return self.t


def test_playback_frame_is_elapsed_time_times_rate():
    assert playback_frame(0.0, 60.0) == 0
    assert playback_frame(1.0, 60.0) == 60
    assert playback_frame(5 / 60, 60.0) == 5  # exactly on a frame boundary despite rounding
    assert playback_frame(0.999 / 60, 60.0) == 0
    assert playback_frame(0.5, 60.0, start=10) == 40
    assert playback_frame(1.0, 60.0, speed=0.25) == 15
    assert playback_frame(-3.0, 60.0, start=7) == 7  # before the start: the start frame
    with pytest.raises(ValueError, match="rate"):
        playback_frame(1.0, 0.0)
    with pytest.raises(ValueError, match="speed"):
        playback_frame(1.0, 60.0, speed=float("nan"))


def test_clock_drops_frames_when_ticks_come_late_and_stops_at_the_end():
    fake = FakeClock()
    c = PlaybackClock(60.0, 100, clock=fake)
    with pytest.raises(RuntimeError, match="not been started"):
        c.frame()
    c.start(10)
    assert c.frame() == 10
    fake.t += 0.1  # one tick 100 ms late: frames 11..15 are skipped, not shown late
    assert c.frame() == 16
    fake.t += 0.6 / 60
    assert c.frame() == 17  # the nearest frame: 16.6 frame periods in
    fake.t += 0.2 - 0.6 / 60
    assert c.frame() == 28
    fake.t += (99 - 28) / 60 + 0.001
    assert c.frame() == 99  # the last frame
    fake.t += 1 / 60
    assert c.frame() is None  # past the end
    with pytest.raises(IndexError, match="out of range"):
        c.start(100)


def test_clock_looks_ahead_by_the_measured_display_latency():
    fake = FakeClock()
    c = PlaybackClock(60.0, 1000, clock=fake, latency_window=5)
    c.start(0)
    fake.t += 1.0
    assert c.frame() == 60
    c.shown(chosen_at=fake.t, shown_at=fake.t + 0.05)  # frames take 50 ms to reach the screen
    assert c.latency_s == pytest.approx(0.05)
    assert c.frame() == 63  # the frame due when it will be on screen
    assert c.due() == 60  # what is due now is unchanged
    for _ in range(2):
        c.shown(chosen_at=fake.t, shown_at=fake.t + 0.05)
    c.shown(chosen_at=0.0, shown_at=10.0)  # one stall (capped at 0.25 s) does not move the estimate
    assert c.latency_s == pytest.approx(0.05)
    for _ in range(5):
        c.shown(chosen_at=0.0, shown_at=0.02)  # only the latest 5 count
    assert c.latency_s == pytest.approx(0.02)


def test_clock_speed_and_validation():
    fake = FakeClock()
    c = PlaybackClock(60.0, 1000, speed=0.5, clock=fake)
    c.start(0)
    fake.t += 1.0
    assert c.frame() == 30
    with pytest.raises(ValueError, match="n_frames"):
        PlaybackClock(60.0, 0)
    with pytest.raises(ValueError, match="latency_window"):
        PlaybackClock(60.0, 5, latency_window=0)

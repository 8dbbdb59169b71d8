"""Playback timing from elapsed time (app.models.playback): pure functions with a fake clock, no display."""
from __future__ import annotations

import pytest

from app.models.playback import PlaybackClock, playback_frame


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
    c = PlaybackClock(60.0, 1000, clock=fake, latency_window=5, lead_s=0.0)
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


def test_look_ahead_covers_all_but_the_slowest_recent_frame():
    c = PlaybackClock(60.0, 1000, latency_window=15)
    for v in [0.010] * 10 + [0.020, 0.030, 0.040]:
        c.shown(chosen_at=0.0, shown_at=v)
    assert c.latency_s == pytest.approx(0.030)  # not the upper quartile (10 ms): 2 of 13 frames slower
    c.shown(chosen_at=0.0, shown_at=1.0)  # one stall is ignored ...
    assert c.latency_s == pytest.approx(0.040)
    c.shown(chosen_at=0.0, shown_at=0.2)  # ... two are not: the machine has become slow
    assert c.latency_s == pytest.approx(0.2)


def test_picture_aims_ahead_of_the_sound_by_the_lead_at_the_typical_latency():
    """The look-ahead is the median latency plus lead_s (default 15 ms, the centre of the
    broadcast lip-sync window) unless the second-largest latency is larger."""
    fake = FakeClock()
    c = PlaybackClock(60.0, 1000, clock=fake, latency_window=15)
    assert c.lead_s == pytest.approx(0.015) and c.look_ahead_s == 0.0  # nothing measured: no look-ahead
    for _ in range(10):
        c.shown(chosen_at=0.0, shown_at=0.020)  # steady 20-ms frames
    assert c.latency_s == pytest.approx(0.020) and c.look_ahead_s == pytest.approx(0.035)
    c.start(0)
    fake.t += 1.0
    # on screen at media 1.020 s (frame 61.2, nearest 61); aimed 15 ms ahead, at 1.035 s: frame 62
    assert c.frame() == 62
    # a slow stretch whose second-largest latency exceeds median + lead takes over
    for v in (0.050, 0.060, 0.070):
        c.shown(chosen_at=0.0, shown_at=v)
    assert c.latency_s == pytest.approx(0.060) and c.look_ahead_s == pytest.approx(0.060)
    # with no lead the same stretch aims at the percentile alone, steady frames at the median alone
    d = PlaybackClock(60.0, 1000, latency_window=15, lead_s=0.0, latencies=[0.010] * 10)
    assert d.look_ahead_s == pytest.approx(0.010)
    with pytest.raises(ValueError, match="lead_s"):
        PlaybackClock(60.0, 10, lead_s=-0.01)
    with pytest.raises(ValueError, match="lead_s"):
        PlaybackClock(60.0, 10, lead_s=float("nan"))


def test_clock_never_steps_back_when_the_look_ahead_shrinks():
    fake = FakeClock()
    c = PlaybackClock(60.0, 1000, clock=fake, latency_window=1, lead_s=0.0)
    c.start(0)
    fake.t += 1.0
    c.shown(chosen_at=fake.t, shown_at=fake.t + 0.1)  # a slow frame: look 6 frames ahead
    assert c.frame() == 66
    c.shown(chosen_at=fake.t, shown_at=fake.t)  # the next was fast: no look-ahead
    fake.t += 1 / 60
    assert c.frame() == 66  # held (61 is due), never back to a frame already passed
    fake.t += 6 / 60
    assert c.frame() == 67  # the clock catches up and the picture moves on
    c.start(10)  # a new start may go back
    assert c.frame() == 10


def test_clock_seeded_with_earlier_latencies_looks_ahead_from_its_first_frame():
    fake = FakeClock()
    c = PlaybackClock(60.0, 1000, clock=fake, latency_window=3, latencies=(0.2, 0.05, 0.05, 0.02), lead_s=0.0)
    assert c.latencies == (0.05, 0.05, 0.02)  # the window keeps the latest
    assert c.latency_s == pytest.approx(0.05)
    c.start(0)
    fake.t += 1.0
    assert c.frame() == 63  # looks 3 frames ahead from the first frame on
    assert PlaybackClock(60.0, 10, clock=fake).latency_s == 0.0  # unseeded: no look-ahead until measured
    with pytest.raises(ValueError, match="finite"):
        PlaybackClock(60.0, 10, latencies=(float("nan"),))


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


def test_clock_follows_the_audio_position_once_it_moves():
    fake = FakeClock(0.0)
    audio = {"p": None}
    c = PlaybackClock(60.0, 1000, clock=fake, position=lambda: audio["p"], resync_s=0.1, slew=0.25)
    c.start(0)
    fake.t = 0.05  # no sound yet: the monotonic clock runs
    assert c.frame() == 3 and not c.following_audio
    audio["p"] = 0.0  # the player reports a position that has not moved: not news
    fake.t = 0.15
    assert c.frame() == 9 and not c.following_audio
    audio["p"] = 0.01  # the sound starts moving 0.15 s late: the clock takes its position at once
    assert c.frame() == 1 and c.following_audio and c.n_resyncs == 0
    assert c.media_time() == pytest.approx(0.01)
    fake.t += 0.1  # no new position: runs on at the speed
    assert c.media_time() == pytest.approx(0.11)
    audio["p"] = 0.12  # a small error (10 ms) is slewed, a quarter at a time
    c.sync()
    assert c.media_time() == pytest.approx(0.11 + 0.25 * 0.01)
    c.sync()  # the same position again is not news
    assert c.media_time() == pytest.approx(0.11 + 0.25 * 0.01)
    audio["p"] = 1.0  # a jump (a seek, a stall) beyond resync_s is taken at once
    assert c.frame() == 60 and c.n_resyncs == 1
    audio["p"] = float("nan")  # a nonsense position is ignored
    fake.t += 0.5
    assert c.frame() == 90


def test_clock_keeps_with_audio_that_runs_slow_where_the_wall_clock_drifts():
    fake = FakeClock(0.0)
    rate, drift = 60.0, 0.99  # the sound card runs 1 % slow: 6 frames behind the wall clock after 10 s
    audio_t0 = 0.08
    c = PlaybackClock(rate, 10_000, clock=fake, position=lambda: round(max(0.0, fake.t - audio_t0) * drift, 3))
    c.start(0)
    worst = 0.0
    for i in range(1, 601):  # 10 s of ticks at 60 Hz; positions move in 1-ms steps
        fake.t = i / 60
        k = c.frame()
        heard = max(0.0, fake.t - audio_t0) * drift
        if fake.t > audio_t0 + 0.05:
            worst = max(worst, abs(c.media_time() - heard))
    assert c.following_audio and c.n_resyncs == 0
    assert worst < 0.5 / rate  # within half a frame period of what is heard, all along
    assert abs(k - heard * rate) <= 1
    assert (fake.t - heard) * rate > 6  # the wall clock alone would be 6+ frames off by now


def test_next_tick_is_when_the_next_frame_becomes_the_nearest_on_screen():
    fake = FakeClock(0.0)
    c = PlaybackClock(50.0, 100, clock=fake, lead_s=0.0)  # 20-ms frames
    c.start(0)
    c.shown(chosen_at=0.0, shown_at=0.004)  # 4 ms from choosing a frame to its being on screen
    assert c.frame() == 0
    # frame 1 is nearest from media 10 ms on; on screen 4 ms after it is chosen: choose it at 6 ms
    assert c.next_tick_in(0) == pytest.approx(0.006)
    fake.t = 0.006 - 1e-6
    assert c.frame() == 0
    fake.t = 0.006 + 1e-6
    assert c.frame() == 1
    assert c.next_tick_in(1) == pytest.approx(0.020 - 1e-6)
    assert c.next_tick_in(0) == 0.0  # overdue
    assert c.next_tick_in(40) == pytest.approx(0.020)  # never more than a frame period
    assert c.next_tick_in(None) == 0.0
    c.speed = 0.5
    c.start(10)
    assert c.next_tick_in(60) == pytest.approx(0.040)  # a frame period at half speed
    assert c.lag_frames(10) == pytest.approx(0.0)
    fake.t += 0.1
    assert c.lag_frames(10) == pytest.approx(2.5)  # 0.1 s at half speed, 50 Hz
    assert c.lag_frames(14) == pytest.approx(-1.5)  # early


def test_clock_audio_options_are_validated():
    with pytest.raises(ValueError, match="resync_s"):
        PlaybackClock(60.0, 5, resync_s=0.0)
    with pytest.raises(ValueError, match="slew"):
        PlaybackClock(60.0, 5, slew=1.5)


# --------------------------------------------------------------------------- the real lip view (Xvfb)
@pytest.fixture
def lip_view(qapp, app_manifold):
    from app.models.state import AppState
    from app.views.lip_view import LipView

    s = AppState(app_manifold)
    u = max(app_manifold.corpus_.utterances, key=lambda u: u.stop - u.start)
    s.set_utterance(u.id)
    view = LipView(s)
    view.resize(480, 360)
    view.show()
    for _ in range(5):
        qapp.processEvents()
    yield view
    s.set_playing(False)
    view.close_view()
    view.deleteLater()
    qapp.processEvents()


def _play(qapp, view, seconds, position=None):
    """Press Play and run the event loop; returns [(monotonic time, frame on screen)] at each swap."""
    import time

    swaps = []
    view.plotter.interactor.frameSwapped.connect(lambda: swaps.append((time.monotonic(), view.shown_frame)))
    if position is not None:
        view.position_source = position
    t0 = time.monotonic()
    view.state.set_playing(True)
    while time.monotonic() - t0 < seconds and view.state.playing:
        qapp.processEvents()
        time.sleep(0.001)
    return t0, [(t, k) for t, k in swaps if k is not None]


@pytest.mark.gui
def test_real_playback_advances_by_elapsed_time(qapp, lip_view):
    s = lip_view.state
    rate = s.original.rate
    t0, swaps = _play(qapp, lip_view, 1.0)
    clock = lip_view.clock
    s.set_playing(False)
    assert len({k for _, k in swaps}) >= 5  # frames reach the screen (dropped ones skipped, not queued)
    assert [k for _, k in swaps] == sorted(k for _, k in swaps)
    assert not clock.following_audio  # no sound here: the monotonic clock
    t_last, k_last = swaps[-1]
    # the frame on screen is the one due by elapsed time (nearest, looking ahead by the
    # display latency, itself capped at 0.25 s) - not one per tick, not stuck behind
    assert -0.5 - 0.25 * rate <= (t_last - t0) * rate - k_last <= 0.5 + 0.25 * rate
    assert k_last >= 0.5 * rate * (t_last - t0) - 3
    # the readouts are up to date once playback stops
    qapp.processEvents()
    assert lip_view.slider.value() == s.playback
    assert f"playback frame {s.playback + 1}/" in lip_view.caption.text()


@pytest.mark.gui
def test_real_playback_follows_the_audio_position(qapp, lip_view):
    import time

    rate = lip_view.state.original.rate
    t_play = [None]

    def heard():  # a sound card that starts 0.1 s late, plays at 0.5x and reports in 20-ms steps
        if t_play[0] is None:
            t_play[0] = time.monotonic()
        t = time.monotonic() - t_play[0] - 0.1
        return None if t < 0 else 0.02 * int(0.5 * t / 0.02)

    t0, swaps = _play(qapp, lip_view, 1.2, position=heard)
    clock = lip_view.clock
    lip_view.state.set_playing(False)
    assert clock.following_audio
    late = [(t, k) for t, k in swaps if t - t0 > 0.3]
    assert len({k for _, k in late}) >= 3
    for t, k in late:  # near what is heard (the monotonic clock alone would be 2x ahead by the end)
        assert abs(k - 0.5 * (t - t0 - 0.1) * rate) <= 0.25 * 0.5 * rate + 2
    t_last, k_last = late[-1]
    assert k_last < 0.75 * (t_last - t0) * rate


@pytest.mark.gui
def test_throttle_runs_at_most_once_per_slot_and_ends_on_the_latest(qapp):
    from app.views._common import Throttle

    now = [10.0]
    calls = []
    th = Throttle(calls.append, 0.2, clock=lambda: now[0])
    th(1)  # the first call of a slot runs at once
    th(2)
    th(3)  # held, replacing 2
    assert calls == [1]
    now[0] = 10.21  # the next slot: runs at once, the held one dropped
    th(4)
    assert calls == [1, 4]
    th(5)
    th.flush()
    assert calls == [1, 4, 5]
    th(6)
    th.cancel()
    th.flush()
    assert calls == [1, 4, 5]
    with pytest.raises(ValueError, match="interval_s"):
        Throttle(calls.append, 0.0)


@pytest.mark.gui
def test_readouts_called_while_a_frame_is_drawn_repaint_just_after_it(qapp, qtbot):
    from PySide6 import QtCore, QtWidgets

    from app.views._common import Throttle, drawing_frame

    label = QtWidgets.QLabel("")
    qtbot.addWidget(label)
    label.resize(200, 40)
    # on screen first: X maps and exposes the window asynchronously, and Qt paints no window
    # before it is exposed (a few processEvents() were not always enough on a busy machine)
    with qtbot.waitExposed(label, timeout=10000):
        label.show()
    for _ in range(5):
        qapp.processEvents()
    paints = []

    class PaintLog(QtCore.QObject):
        def eventFilter(self, obj, event):  # noqa: N802 - Qt override
            if event.type() == QtCore.QEvent.Type.Paint:
                paints.append(label.text())
            return False

    log = PaintLog()
    label.installEventFilter(log)
    now = [10.0]
    th = Throttle(label.setText, 0.5, clock=lambda: now[0])
    try:
        with drawing_frame():
            with drawing_frame():  # nested: only the outermost exit releases
                th("frame 1")  # the first call of a slot, yet held while the frame is drawn
                assert label.text() == "" and paints == []
            th("frame 2")  # the latest call wins
            assert label.text() == ""
        # released at the exit, and painted there (not left for a later turn of the event loop)
        assert label.text() == "frame 2"
        assert paints and paints[-1] == "frame 2"
        with drawing_frame():
            th("frame 3")  # the same slot: still held after this frame
        assert label.text() == "frame 2"
        now[0] = 10.45
        with drawing_frame():
            th("frame 4")
        assert label.text() == "frame 2"
        now[0] = 10.51  # the next slot has come: the first frame drawn in it releases the latest call
        with drawing_frame():
            pass
        assert label.text() == "frame 4" and paints[-1] == "frame 4"
        th("frame 5")  # same slot, outside a frame: held for the next slot as before
        assert label.text() == "frame 4"
        now[0] = 11.1
        th("frame 6")
        assert label.text() == "frame 6"
    finally:
        th.cancel()
        label.removeEventFilter(log)
        label.close()


@pytest.mark.gui
def test_no_readout_paints_between_a_frames_choice_and_its_swap(qapp, lip_view):
    import time

    from PySide6 import QtCore

    s = lip_view.state
    marks = []  # (time, what)
    # frames chosen while playing (the last frame, shown as playback stops, comes with the readouts)
    s.events.playback.connect(lambda _k: s.playing and marks.append((time.monotonic(), "chosen")))
    lip_view.plotter.interactor.frameSwapped.connect(lambda: marks.append((time.monotonic(), "swap")))

    class PaintLog(QtCore.QObject):
        def eventFilter(self, obj, event):  # noqa: N802 - Qt override
            if event.type() == QtCore.QEvent.Type.Paint:
                marks.append((time.monotonic(), "readout"))
            return False

    log = PaintLog()
    for w in (lip_view.caption, lip_view.slider):
        w.installEventFilter(log)
    try:
        _play(qapp, lip_view, 1.2)
        s.set_playing(False)
    finally:
        for w in (lip_view.caption, lip_view.slider):
            w.removeEventFilter(log)
    kinds = [m for _, m in sorted(marks)]
    kinds = kinds[kinds.index("swap") + 1:]  # from the first frame on screen (Play itself set frame 0)
    assert kinds.count("readout") >= 2  # the readouts do follow playback
    assert kinds.count("swap") >= 5
    pending = False  # a frame chosen and not yet on screen
    for kind in kinds:
        if kind == "chosen":
            pending = True
        elif kind == "swap":
            pending = False
        else:
            assert not pending, f"a readout painted between a frame's choice and its swap: {kinds}"


@pytest.mark.gui
def test_next_playback_looks_ahead_by_the_latencies_the_last_one_measured(qapp, lip_view):
    s = lip_view.state
    lip_view._latencies = ((), None)  # nothing measured yet: Play draws the shown frame once to measure
    s.set_playback(0)
    s.set_playing(True)
    assert len(lip_view.clock.latencies) == 1 and 0 < lip_view.clock.latency_s <= 0.25
    s.set_playing(False)
    _play(qapp, lip_view, 0.5)
    measured = lip_view.clock.latencies
    s.set_playing(False)
    assert measured and all(0 < v <= 0.25 for v in measured)
    s.set_playback(0)
    s.set_playing(True)
    assert lip_view.clock.latencies == measured  # a new clock, seeded: its first frame looks ahead too
    s.set_playing(False)

"""bench_gui_playback's frame table and late-frame causes (benchmarks/_playback_trace.py), on made-up time stamps."""
from __future__ import annotations

import os
import sys

import numpy as np

_REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
sys.path[:0] = [os.path.join(_REPO, "benchmarks"), os.path.join(_REPO, "tools")]  # _playback_trace, steal_probe
from _playback_trace import frame_table, late_causes  # noqa: E402

RATE = 100.0  # 10-ms frame periods


def _run(frames):
    """frames: (chosen at, look-ahead, render ms, compose ms, GUI thread run wait ms) per frame k = 0, 1, ..."""
    ticks, rs, re, swaps = [], [], [], []
    wait = 0.0
    for k, (t, la, render, compose, w) in enumerate(frames):
        ticks.append((t, k, la, t - 0.001, 0.0, wait))
        r0 = t + 0.002
        rs.append(r0)
        re.append(r0 + render / 1e3)
        wait += w / 1e3
        swaps.append((r0 + (render + compose) / 1e3, 0.0, wait))
    return ticks, rs, re, swaps


def test_lag_stages_and_causes_of_late_frames():
    frames = [(0.000, 0.01, 4, 2, 0), (0.010, 0.01, 4, 2, 0), (0.020, 0.01, 4, 2, 0),
              (0.030, 0.01, 4, 2, 14),   # 14 ms waiting for a core: preempted
              (0.060, 0.01, 20, 2, 0),   # a 20-ms render
              (0.090, 0.01, 4, 2, 0),    # a 15-ms collection in between
              (0.120, 0.01, 4, 2, 0)]    # the manifold view rendered in between
    ticks, rs, re, swaps = _run(frames)
    # stretch frames 3-6's time to swap by what happened to them
    swaps[3] = (swaps[3][0] + 0.014, *swaps[3][1:])
    swaps[5] = (swaps[5][0] + 0.015, *swaps[5][1:])
    rs[5] += 0.015
    re[5] += 0.015
    swaps[6] = (swaps[6][0] + 0.012, *swaps[6][1:])
    rs[6] += 0.012
    re[6] += 0.012
    gcs = [(0.0915, 0.1065, 2)]
    tab = frame_table(ticks, rs, re, swaps, [0.1205], [0.1325], gcs, t0=0.0, rate=RATE)
    assert list(tab["frame"]) == list(range(7))
    # lag = clock at the swap in frames minus the frame: frame 0 swaps at 8 ms -> 0.8 periods
    assert np.isclose(tab["lag"][0], 0.8)
    assert np.allclose(tab["render"][:4] * 1e3, 4) and np.isclose(tab["render"][4] * 1e3, 20)
    assert np.isclose(tab["timer_late"][0], 0.001)
    assert np.isclose(tab["run_wait"][3], 0.014) and tab["run_wait"][2] == 0
    assert np.isclose(tab["gc"][5], 0.015) and np.isclose(tab["other_view"][6], 0.012)
    late = np.flatnonzero(tab["lag"] > 1)
    assert list(late) == [3, 4, 5, 6]
    assert late_causes(tab, rate=RATE) == ["preempted", "long render", "gc", "other view"]


def test_a_frame_rendered_twice_counts_once_at_its_first_swap():
    ticks, rs, re, swaps = _run([(0.0, 0.0, 4, 2, 0), (0.010, 0.0, 4, 2, 0)])
    # the main window's composition re-swaps the lip window with frame 1 still in it
    rs.append(0.025)
    re.append(0.027)
    swaps.append((0.028, 0.0, 0.0))
    tab = frame_table(ticks, rs, re, swaps, [], [], [], t0=0.0, rate=RATE)
    assert list(tab["frame"]) == [0, 1]
    assert np.allclose(tab["swap"], [0.008, 0.018])
    assert late_causes(tab, rate=RATE) == []


def _counters(core, cpu, steal, irq=(0.0, 0.0), utime=0.0, minflt=0, vm=(0, 0, 0, 0, 0)):
    from _playback_trace import Counters

    return Counters(core, cpu, utime, 0.0, minflt, 0, tuple(steal), tuple(irq), tuple(vm))


def test_proc_text_parsing():
    from _playback_trace import parse_proc_stat, parse_task_stat

    stat = ("cpu  3090495 130233 571964 1126664 11559 0 4189 68160 0 0\n"
            "cpu0 1474983 65911 267514 655070 3065 7 759 34064 0 0\n"
            "cpu1 1615512 64322 304450 471594 8494 0 3430 34096 0 0\n"
            "intr 20620274 0 0\nctxt 44081423\n")
    steal, irq = parse_proc_stat(stat)
    assert steal == (340.64, 340.96) and irq == (7.66, 34.30)
    # a command name with spaces and a parenthesis must not shift the fields
    task = ("4242 (python (x) y) R 1 2 3 0 -1 4194304 1500 0 7 0 250 36 0 0 20 0 9 0 100 1000 200 "
            "18446744073709551615 1 1 0 0 0 0 0 16781312 17642 0 0 0 17 1 0 0 0 0 0")
    assert parse_task_stat(task) == (1, 2.50, 0.36, 1500, 7)


def test_steal_on_the_gui_threads_core_is_a_cause_and_long_frames_are_split_by_it():
    from _playback_trace import long_frames

    frames = [(0.000, 0.01, 4, 2, 0), (0.010, 0.01, 4, 2, 0), (0.020, 0.01, 4, 2, 0), (0.030, 0.01, 4, 2, 0),
              (0.080, 0.01, 4, 2, 0), (0.200, 0.01, 4, 2, 0)]
    ticks, rs, re, swaps = _run(frames)
    # frame 3: 30 ms longer to its swap, and core 1 (where the GUI thread is) lost 40 ms to steal by the counter
    # (10-ms steps); core 0 lost more, but the GUI thread was not on it
    swaps[3] = (swaps[3][0] + 0.030, *swaps[3][1:])
    # frame 4: 90 ms of the GUI thread's own CPU more than usual, with no steal (a long frame not explained by it)
    swaps[4] = (swaps[4][0] + 0.090, *swaps[4][1:])
    # frame 5: a long frame whose excess CPU the steal on its core covers (the thread migrated 0 -> 1); frame 4's
    # core shows 100 ms of steal only at the next tick (frame 5's choice): by then it covers frame 4's excess
    steal0 = {0: (0.0, 0.0), 1: (0.0, 0.0), 2: (0.0, 0.0), 3: (0.50, 0.0), 4: (0.6, 0.04), 5: (0.6, 0.14)}
    steal1 = {0: (0.0, 0.0), 1: (0.0, 0.0), 2: (0.0, 0.0), 3: (0.60, 0.04), 4: (0.6, 0.04), 5: (0.61, 0.19)}
    cpu0 = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    cpu1 = [0.006, 1.006, 2.006, 3.006, 4.096, 5.056]
    core0 = [1, 1, 1, 1, 1, 0]
    # with the helper threads' and X server's waits (0 here) before the readings, as PlaybackTrace records them
    ticks = [(*x, 0.0, 0.0, _counters(core0[i], cpu0[i], steal0[i])) for i, x in enumerate(ticks)]
    swaps = [(*x, 0.0, 0.0, _counters(1, cpu1[i], steal1[i])) for i, x in enumerate(swaps)]
    tab = frame_table(ticks, rs, re, swaps, [], [], [], t0=0.0, rate=RATE)
    assert np.allclose(tab["steal"], [0, 0, 0, 0.04, 0, 0.06])
    assert np.allclose(tab["steal_all"], [0, 0, 0, 0.14, 0, 0.06])
    assert list(tab["migrated"]) == [0, 0, 0, 0, 0, 1]
    assert np.allclose(tab["thread_cpu"], [0.006] * 4 + [0.096, 0.056])
    late = np.flatnonzero(tab["lag"] > 1)
    assert list(late) == [3, 4, 5]
    assert late_causes(tab, rate=RATE)[0] == "steal"
    longs = long_frames(tab)
    assert [lf["frame"] for lf in longs] == [4, 5]
    assert [lf["steal_explains"] for lf in longs] == [False, True]
    assert np.allclose(tab["steal_next"][3:5], [0.04, 0.10])
    assert [lf["steal_next_explains"] for lf in longs] == [True, True]
    assert np.isclose(longs[0]["excess"], 0.090)


def test_without_counter_readings_steal_is_not_blamed():
    ticks, rs, re, swaps = _run([(0.0, 0.01, 4, 2, 0), (0.010, 0.01, 4, 2, 25)])
    swaps[1] = (swaps[1][0] + 0.025, *swaps[1][1:])
    tab = frame_table(ticks, rs, re, swaps, [], [], [], t0=0.0, rate=RATE)
    assert np.isnan(tab["steal"]).all()
    assert late_causes(tab, rate=RATE) == ["preempted"]


def test_steal_probe_splits_charged_pieces_by_reported_steal():
    import steal_probe

    rows = steal_probe.probe(0.15, 0.0)
    assert len(rows) > 10 and (rows[:, 1] >= rows[:, 0]).all() and (rows[:, 2] >= 0).all()
    assert set(rows[:, 4].astype(int)) <= set(range(os.cpu_count()))
    # made up: 0.2-ms pieces; one charged 50 ms with 40 ms of steal on its core seen only at the next piece,
    # one charged 30 ms with none
    fake = np.zeros((20, 7))
    fake[:, 0] = np.arange(20) * 0.01
    fake[:, 1] = fake[:, 0] + 0.0002
    fake[:, 2] = 0.0002
    fake[3, 2], fake[3, 6] = 0.050, 0.040
    fake[9, 2] = 0.030
    line = steal_probe.summary(fake)[2]
    assert "charged > 10x the median own CPU: 2 (80 ms beyond the median)" in line
    assert line.endswith("by the next piece: 1, without: 1")

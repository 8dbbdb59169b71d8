"""bench_gui_playback's frame table and late-frame causes (benchmarks/_playback_trace.py), on made-up time stamps."""
from __future__ import annotations

import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                                "benchmarks"))
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

"""Benchmark: playback in the real explorer window — frames per second and lag behind the clock.

Usage: python benchmarks/bench_gui_playback.py [--repeats 3] [--max-seconds 15] [--preset default]

Drives ``app.main_window.MainWindow`` on the default synthetic talker (28,800 frames,
60 Hz) under an X server (re-runs itself under ``xvfb-run`` without one; software
OpenGL). Loads the longest utterance, synthesises it with the linear method (so the
lip view shows the original and the synthetic lips side by side, as a user would
compare them) and presses Play. The reference is the clock a sound track would follow:
frame ``floor(t * rate)`` is due ``t`` seconds after Play was pressed.

For every lip-view frame that reaches the screen (the widget's ``frameSwapped``) the
script records the frame shown (the playback index when the lip view last rendered)
and its lag: how many frame periods the clock is ahead of the shown frame at that
moment (0 <= lag < 1 means the right frame is on screen; negative means early).
Printed per repeat and as min / median over repeats: distinct frames shown per second,
max and 99th-percentile lag, frames dropped, manifold-view renders during playback, and
the process's CPU time per frame shown (all threads, the software rasteriser's included;
on a machine shared with other work the wall-clock figures drop while this one holds).
A repeat stops at the end of the utterance or after ``--max-seconds``.

Goals (issue 9 item 4): >= 30 frames/s in the lip view; lag never above one frame period.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _gui_bench as gb  # noqa: E402


def play_once(app, win, llog, mlog, max_seconds):
    import numpy as np

    s = win.state
    rate = (s.original or s.synthetic).rate
    n = s.n_playback
    s.set_playing(False)
    s.set_playback(0)
    gb.settle(app, 0.5)
    shown_at_render: list[tuple[float, int]] = []
    obs = win.lip_view.plotter.render_window.AddObserver(
        "EndEvent", lambda *_a: shown_at_render.append((time.perf_counter(), s.playback)))
    n_swaps, n_mr = len(llog.swaps), len(mlog.renders)
    c0 = time.process_time()
    t0 = time.perf_counter()
    win.lip_view.play_btn.click()  # the user presses Play
    while s.playing and time.perf_counter() - t0 < max_seconds:
        app.processEvents()
        time.sleep(0.0005)
    t_end = time.perf_counter()
    cpu = time.process_time() - c0
    s.set_playing(False)
    win.lip_view.plotter.render_window.RemoveObserver(obs)
    # each swap shows the frame of the latest lip render before it
    rows = []
    r_times = np.array([t for t, _ in shown_at_render])
    for t_swap in llog.swaps[n_swaps:]:
        j = int(np.searchsorted(r_times, t_swap)) - 1
        if j >= 0 and shown_at_render[j][1] is not None:
            rows.append((t_swap, shown_at_render[j][1]))
    # distinct frames, at the time each first reached the screen
    first = {}
    for t_swap, k in rows:
        first.setdefault(k, t_swap)
    ks = np.array(sorted(first))
    ts = np.array([first[k] for k in ks])
    lag = (ts - t0) * rate - ks  # frame periods the clock is ahead of the shown frame
    duration = t_end - t0
    dropped = int(ks.max() + 1 - len(ks)) if len(ks) else 0
    return {"fps": len(ks) / duration, "frames": len(ks), "last": int(ks.max()) if len(ks) else -1, "n": n,
            "duration": duration, "max_lag": float(lag.max()) if len(lag) else float("nan"),
            "p99_lag": float(np.percentile(lag, 99)) if len(lag) else float("nan"),
            "min_lag": float(lag.min()) if len(lag) else float("nan"), "over1": int((lag > 1).sum()),
            "dropped": dropped, "manifold_renders": len(mlog.renders) - n_mr, "cpu": cpu}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--max-seconds", type=float, default=15.0, help="stop a repeat after this long")
    ap.add_argument("--preset", default="default")
    args = ap.parse_args()
    gb.ensure_display()
    import numpy as np

    gb.header("playback in the lip view (real window, Play button)")
    t_all = time.perf_counter()
    m, src = gb.default_manifold(args.preset)
    app, win = gb.open_window(m, src)
    c = m.corpus_
    u = max(c.utterances, key=lambda u: u.stop - u.start)
    from engine import targets as T
    from app.views.trajectory_editor import synthesize_targets

    win.state.set_utterance(u.id)
    data, _ = synthesize_targets(m, T.targets_from_utterance(m, u.id, on_collision="merge"), "linear")
    win.state.set_trajectories(synthetic=data)
    gb.settle(app, 0.5)
    lips = win.lip_view.plotter
    print(f"   OpenGL renderer: {gb.gl_renderer(lips)}; window {gb.WINDOW_SIZE[0]}x{gb.WINDOW_SIZE[1]}, lip view "
          f"{lips.render_window.GetSize()[0]}x{lips.render_window.GetSize()[1]} px, manifold view "
          f"{win.manifold_view.plotter.render_window.GetSize()[0]}x{win.manifold_view.plotter.render_window.GetSize()[1]}")
    print(f"   utterance {u.id}: {u.stop - u.start} frames at {c.rate:g} Hz ({(u.stop - u.start) / c.rate:.2f} s), "
          f"original + synthetic (linear) side by side, {c.n_points} points per lip frame")
    llog, mlog = gb.RenderLog(lips), gb.RenderLog(win.manifold_view.plotter)
    res = []
    for r in range(args.repeats):
        x = play_once(app, win, llog, mlog, args.max_seconds)
        res.append(x)
        print(f"   repeat {r + 1}: {x['fps']:5.1f} frames/s shown ({x['frames']} distinct frames, up to frame "
              f"{x['last'] + 1}/{x['n']} in {x['duration']:.2f} s, {x['dropped']} dropped); lag max {x['max_lag']:.2f}, "
              f"99th pct {x['p99_lag']:.2f}, min {x['min_lag']:.2f} frame periods, {x['over1']} frames > 1 behind; "
              f"{x['manifold_renders']} manifold-view renders; process CPU {x['cpu']:.2f} s = "
              f"{1e3 * x['cpu'] / max(x['frames'], 1):.1f} ms per frame shown", flush=True)
    fps = [x["fps"] for x in res]
    lag = [x["max_lag"] for x in res]
    print(f"frames/s shown:            min {min(fps):.1f}, median {np.median(fps):.1f} (goal >= 30)")
    print(f"max lag (frame periods):   min {min(lag):.2f}, median {np.median(lag):.2f}, worst {max(lag):.2f} (goal <= 1)")
    print(f"wall {time.perf_counter() - t_all:.1f} s; peak RSS {gb.peak_rss_mb():.0f} MiB; "
          f"load average {os.getloadavg()[0]:.1f} at end")
    win.close()


if __name__ == "__main__":
    main()

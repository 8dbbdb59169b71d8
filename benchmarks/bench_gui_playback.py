"""Benchmark: playback in the real explorer window — frames per second and lag behind the clock.

Usage: python benchmarks/bench_gui_playback.py [--repeats 4] [--max-seconds 15] [--preset default]
       [--tree DIR] [--probe] [--manifold FILE|talker ...] [--rounds 1]

Drives ``app.main_window.MainWindow`` on the default synthetic talker (28,800 frames,
60 Hz), or on the manifold given with ``--manifold`` (any size, blocked corpora
included), under an X server (re-runs itself under ``xvfb-run`` without one; software
OpenGL). With several ``--manifold`` files (``talker`` names the default talker) each
is played in fresh processes, alternating, ``--rounds`` times, and the frame rates and
lags are printed side by side. Loads the longest utterance, synthesises it with the linear method (so the
lip view shows the original and the synthetic lips side by side, as a user would
compare them) and presses Play, then runs the Qt event loop as the explorer does. There
is no sound device here, so the reference is the clock a sound track would set:
the playback clock's media time (``app.models.playback.PlaybackClock``, started in Play's
handler; the delay from the press to that start is printed separately), frame ``k``
due at ``k / rate``.

For every lip-view frame that reaches the screen (the widget's ``frameSwapped``) the
script records the frame on screen (the frame in the lip meshes when the lip view last
rendered) and its **lag**: ``clock * rate - k`` in frame periods at the swap (0 = on
time, 1 = a whole frame period late, negative = early). Printed per repeat: distinct
frames shown per second, the lag's median, 95th and 99th percentiles, max and min, the
fraction of frames more than one period late (and more than one early), the *held* lag
(the lag just before the next frame replaced it: how stale the screen got), frames
dropped, compositions of the main window (frame swaps of the manifold view's widget,
which Qt composes with the main window) and manifold-view renders, the process's CPU
time per frame shown (all threads, the software rasteriser's included) and the load
average. Then each frame's stages (``_playback_trace``): choice -> render start, the
VTK render, render end -> swap; how late the playback timer fired; garbage collections
(``gc.callbacks``); how long the GUI thread, the rasteriser thread that waited most and
the X server were runnable but waiting for a core (``/proc/.../schedstat``: other
processes held it); and each frame more than one period late attributed to the largest
of: gc, preempted, other view (a manifold render between its choice and swap), long
render, long compose, queued. Then min / median over repeats; repeat 1 is the first
playback in a fresh process (cold), the others warm.

Each frame's GUI-thread CPU is also read with the hypervisor's steal on its core
(``/proc/stat``; this is a virtual machine): a late frame can be attributed to
``steal``, and each *long frame* (GUI thread CPU > 40 ms between choice and swap) is
listed with its own CPU, the steal on its core and the machine's counters. ``--probe``
runs ``tools/steal_probe.py`` (a fixed 0.2-ms piece of work every 10 ms, in a process of its
own) beside the repeats and prints, for each long frame, how much CPU the probe's pieces
were charged meanwhile: if a fixed piece of work elsewhere is charged many times its
CPU at the same moment, the time was taken from the machine, not by the explorer.

On the virtual machine measured, long frames are time the machine took, charged to the GUI
thread: steal arrives in the counters late and in lumps (a 19-ms frame charged 274 ms of
CPU as its core's steal rose by 440 ms), some of it is never reported as steal, and the
probe's fixed work is charged the same way at the same moments (docs/DECISIONS.md,
I5).

``--tree DIR`` runs the explorer code of another checkout with this same script (e.g.
the commit before a change, extracted with ``git archive REV | tar -x -C DIR``), for
side-by-side figures.

Goals (issue 9 item 4): >= 30 frames/s in the lip view; lag never above one frame period.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _gui_bench as gb  # noqa: E402
from _harness import Harness  # noqa: E402
from _playback_trace import CAUSES, LONG_FRAME_CPU_S, PlaybackTrace, frame_table, late_causes, long_frames  # noqa: E402


def run_loop(app, s, max_seconds):
    """Run the Qt event loop (as the explorer does) until playback stops or ``max_seconds`` pass."""
    from PySide6 import QtCore

    loop = QtCore.QEventLoop()
    t0 = time.perf_counter()
    poll = QtCore.QTimer()
    poll.setInterval(20)
    poll.timeout.connect(lambda: (not s.playing or time.perf_counter() - t0 > max_seconds) and loop.quit())
    poll.start()
    loop.exec()
    poll.stop()


def play_once(app, win, max_seconds):
    import numpy as np

    s, lv = win.state, win.lip_view
    rate = (s.original or s.synthetic).rate
    n = s.n_playback
    s.set_playing(False)
    s.set_playback(0)
    gb.settle(app, 0.5)
    trace = PlaybackTrace()
    main_swaps = []
    on_main = lambda: main_swaps.append(time.perf_counter())  # noqa: E731
    win.manifold_view.plotter.interactor.frameSwapped.connect(on_main)
    trace.attach(win)
    load0 = os.getloadavg()[0]
    c0 = time.process_time()
    t0 = time.perf_counter()
    lv.play_btn.click()  # the user presses Play
    run_loop(app, s, max_seconds)
    t_end = time.perf_counter()
    cpu = time.process_time() - c0
    s.set_playing(False)
    trace.detach()
    win.manifold_view.plotter.interactor.frameSwapped.disconnect(on_main)
    # the reference is the playback clock (what a sound track would follow: media time 0 when the
    # clock started, in Play's handler), not the button press; the press -> start delay is printed
    t_press = t0
    if trace.clock_start is not None:
        t0 = trace.clock_start[0] - trace.clock_start[1] / rate
    tab = frame_table(trace.ticks, trace.render_start, trace.render_end, trace.swaps, trace.m_start, trace.m_end,
                      trace.gcs, t0=t0, rate=rate)
    ks, ts, lag = tab["frame"], tab["swap"], tab["lag"]
    causes = late_causes(tab, rate=rate)
    longs = long_frames(tab)
    for lf in longs:
        lf["cause"] = causes[int(np.sum(tab["lag"][:lf["index"]] > 1))] if lf["lag"] > 1 else "on time"
    # steal over the whole playback, all cores: first tick's reading to the last swap's
    readings = [x[8] for x in trace.ticks if len(x) > 8 and x[8] is not None] + \
        [x[5] for x in trace.swaps if len(x) > 5 and x[5] is not None]
    steal_s = (sum(readings[-1].steal) - sum(readings[0].steal)) if len(readings) > 1 else float("nan")
    # held lag: the clock when the next frame replaced this one (or playback ended)
    t_next = np.append(ts[1:], min(t_end, t0 + n / rate))
    held = (t_next - t0) * rate - ks
    duration = t_end - t_press
    dropped = int(ks.max() + 1 - len(ks)) if len(ks) else 0

    def pct(a, q):
        return float(np.nanpercentile(a, q)) if np.isfinite(a).any() else float("nan")

    late = lag > 1
    return {"fps": len(ks) / duration, "frames": len(ks), "last": int(ks.max()) if len(ks) else -1, "n": n,
            "duration": duration, "lag_med": pct(lag, 50), "lag_p95": pct(lag, 95), "lag_p99": pct(lag, 99),
            "lag_max": float(lag.max()) if len(lag) else float("nan"),
            "lag_min": float(lag.min()) if len(lag) else float("nan"),
            "late": float(late.mean()) if len(lag) else float("nan"),
            "early": float((lag < -1).mean()) if len(lag) else float("nan"),
            "held_p95": pct(held, 95), "held_max": float(held.max()) if len(held) else float("nan"),
            "dropped": dropped, "main_swaps": sum(t >= t_press for t in main_swaps), "m_renders": len(trace.m_end),
            "causes": {c: causes.count(c) for c in CAUSES},
            "timer_late_p95": 1e3 * pct(tab["timer_late"], 95), "timer_late_max": 1e3 * float(np.nanmax(
                tab["timer_late"])) if np.isfinite(tab["timer_late"]).any() else float("nan"),
            "render_med": 1e3 * pct(tab["render"], 50), "render_max": 1e3 * pct(tab["render"], 100),
            "queue_med": 1e3 * pct(tab["queue"], 50), "compose_med": 1e3 * pct(tab["compose"], 50),
            "latency_med": 1e3 * pct(tab["swap"] - tab["chosen"], 50),
            "gcs": [g for g in trace.gcs if g[0] >= t0], "run_wait": 1e3 * float(np.nansum(tab["run_wait"])),
            "late_wait_cpu": [(1e3 * tab["run_wait"][i], 1e3 * tab["helper_wait"][i], 1e3 * tab["cpu"][i],
                               1e3 * (tab["swap"][i] - tab["chosen"][i]), 1e3 * tab["lookahead"][i])
                              for i in np.flatnonzero(late)],
            "helper_wait": 1e3 * float(np.nansum(tab["helper_wait"])),
            "press_ms": 1e3 * (t0 - t_press),
            # what the user sees of the start: Play pressed -> the first frame after frame 0 on screen
            "first_move_ms": 1e3 * (float(ts[np.flatnonzero(ks > 0)[0]]) - t_press) if (ks > 0).any() else float("nan"),
            "cpu": cpu, "cpu_ms": 1e3 * cpu / max(len(ks), 1), "load": (load0 + os.getloadavg()[0]) / 2,
            "longs": longs, "steal_s": steal_s, "steal_late": 1e3 * np.nan_to_num(tab["steal"][late]),
            "thread_cpu_med": 1e3 * pct(tab["thread_cpu"], 50), "thread_cpu_p99": 1e3 * pct(tab["thread_cpu"], 99),
            "thread_cpu_sum": float(np.nansum(tab["thread_cpu"]))}


def _start_probe():
    """``tools/steal_probe.py`` in a process of its own, saving its pieces to a temporary file."""
    import subprocess
    import tempfile

    fd, out = tempfile.mkstemp(suffix=".npy", prefix="steal_probe_")
    os.close(fd)
    script = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "tools", "steal_probe.py")
    proc = subprocess.Popen([sys.executable, script, "--seconds", "86400", "--out", out],
                            stdout=subprocess.PIPE, text=True)
    return proc, out


def _probe_report(probe, res) -> None:
    """Stop the probe; print its summary and, for each long frame, its pieces' own CPU meanwhile."""
    import numpy as np

    longs = [lf for x in res for lf in x["longs"]]
    proc, out = probe
    proc.terminate()
    gui_cpu = sum(x["thread_cpu_sum"] for x in res)
    excess = sum(lf["excess"] for lf in longs)
    text, _ = proc.communicate(timeout=30)
    print(text.rstrip())
    try:
        rows = np.load(out)
    finally:
        os.unlink(out)
    if len(rows) == 0:
        return
    med = float(np.median(rows[:, 2]))
    charged = rows[:, 2] > 10 * med
    # if the machine takes the time, each thread is charged in proportion to the time it runs
    print(f"   share of own CPU charged beyond the usual: GUI thread {100 * excess / max(gui_cpu, 1e-9):.1f} % "
          f"(long frames' excess {1e3 * excess:.0f} ms of {gui_cpu:.1f} s between choices and swaps), probe "
          f"{100 * float(np.sum(rows[charged, 2] - med)) / max(float(rows[:, 2].sum()), 1e-9):.1f} % (pieces over "
          f"10x the median: {1e3 * float(np.sum(rows[charged, 2] - med)):.0f} ms of {float(rows[:, 2].sum()):.2f} s)")
    probe_charged = []
    for lf in longs:
        sel = (rows[:, 1] >= lf["chosen"]) & (rows[:, 0] <= lf["chosen"] + lf["latency"])
        cpu = rows[sel, 2]
        probe_charged.append(bool((cpu > 10 * med).any()))
        print(f"   during long frame {lf['frame']} (own CPU {1e3 * lf['cpu']:.0f} ms, steal on its core "
              f"{1e3 * lf['steal']:.0f}/{1e3 * lf['steal_next']:.0f} ms): {int(sel.sum())} probe pieces, "
              + (f"their own CPU max {1e3 * cpu.max():.2f} ms = {cpu.max() / med:.0f}x the probe's median, "
                 f"{int((cpu > 10 * med).sum())} above 10x, on cores {sorted(int(c) for c in set(rows[sel, 4]))}"
                 if sel.any() else "none (the probe did not run then)"))
    if longs:
        steal = [lf["steal_explains"] for lf in longs]
        print(f"   long frames covered by steal on their core: {sum(steal)} of {len(longs)}; during which the probe "
              f"too was charged > 10x its median: {sum(probe_charged)}; neither: "
              f"{sum(not a and not b for a, b in zip(steal, probe_charged))}")


def _long_line(lf) -> str:
    """One printed line for a long frame (:func:`_playback_trace.long_frames`)."""
    vm = ", ".join(f"{k[3:]} {lf[k]:.0f}" for k in lf if k.startswith("vm_") and lf[k])
    return (f"        long frame {lf['frame']} ({lf['cause']}, lag {lf['lag']:.2f}; chosen at monotonic "
            f"{lf['chosen']:.3f} s): chosen->swap "
            f"{1e3 * lf['latency']:.0f} ms, own CPU {1e3 * lf['cpu']:.0f} ms ({1e3 * lf['excess']:+.0f} over the "
            f"median; user {1e3 * lf['utime']:.0f} / system {1e3 * lf['stime']:.0f} ms in 10-ms ticks), "
            f"steal on its core {1e3 * lf['steal']:.0f} ms (by the next tick {1e3 * lf['steal_next']:.0f}; all cores "
            f"{1e3 * lf['steal_all']:.0f}), interrupt "
            f"ticks {1e3 * lf['irq']:.0f} ms, waited for a core {1e3 * lf['run_wait']:.0f} ms, {lf['minflt']:.0f} "
            f"page faults, core {lf['core']:.0f}{' (migrated)' if lf['migrated'] else ''}; machine: "
            f"{vm or 'no page migration, compaction or huge-page events'}; "
            + ("steal covers the excess" if lf["steal_explains"] else "steal does NOT cover the excess"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=4)
    ap.add_argument("--max-seconds", type=float, default=15.0, help="stop a repeat after this long")
    ap.add_argument("--preset", default="default")
    ap.add_argument("--tree", default=None, help="run the explorer code of this checkout instead of this one")
    ap.add_argument("--probe", action="store_true",
                    help="run tools/steal_probe.py beside the repeats and give its pieces during each long frame")
    gb.add_manifold_argument(ap)
    ap.add_argument("--rounds", type=int, default=1, help="with several --manifold: fresh processes per manifold")
    Harness.add_arguments(ap)
    args = ap.parse_args()
    gb.ensure_display()
    if args.tree:
        sys.path.insert(0, os.path.abspath(args.tree))
    import numpy as np

    cap = gb.apply_max_points(args)
    specs = gb.manifold_specs(args)
    if len(specs) > 1:
        side_by_side(args, specs, cap)
        return

    bench = Harness("bench_gui_playback", args)
    gb.header("playback in the lip view (real window, Play button)")
    import app

    print(f"   explorer code: {os.path.dirname(os.path.dirname(os.path.abspath(app.__file__)))}")
    t_all = time.perf_counter()
    # through whichever loader the tree under test has
    m, src = gb.default_manifold(args.preset) if specs[0] == gb.TALKER else gb.load_manifold(specs[0])
    app_, win = gb.open_window(m, src)
    c = m.corpus_
    u = max(c.utterances, key=lambda u: u.stop - u.start)
    from app.models.trajectories import synthesize_targets
    from engine.phonetics import targets as T

    win.state.set_utterance(u.id)
    data, _ = synthesize_targets(m, T.targets_from_utterance(m, u.id, on_collision="merge"), "linear")
    win.state.set_trajectories(synthetic=data)
    gb.settle(app_, 0.5)
    lips = win.lip_view.plotter
    print(f"   window {gb.WINDOW_SIZE[0]}x{gb.WINDOW_SIZE[1]}, lip view "
          f"{lips.render_window.GetSize()[0]}x{lips.render_window.GetSize()[1]} px, manifold view "
          f"{win.manifold_view.plotter.render_window.GetSize()[0]}x{win.manifold_view.plotter.render_window.GetSize()[1]}")
    print(f"   utterance {u.id}: {u.stop - u.start} frames at {c.rate:g} Hz ({(u.stop - u.start) / c.rate:.2f} s), "
          f"original + synthetic (linear) side by side, {c.n_points} points per lip frame")
    res = []
    probe = _start_probe() if args.probe else None
    for r in range(args.repeats):
        x = play_once(app_, win, args.max_seconds)
        res.append(x)
        print(f"   repeat {r + 1} ({'cold' if r == 0 else 'warm'}, load {x['load']:.1f}): {x['fps']:5.1f} frames/s "
              f"shown ({x['frames']} distinct, up to {x['last'] + 1}/{x['n']} in {x['duration']:.2f} s, "
              f"{x['dropped']} dropped); lag median {x['lag_med']:.2f}, p95 {x['lag_p95']:.2f}, "
              f"p99 {x['lag_p99']:.2f}, "
              f"max {x['lag_max']:.2f}, min {x['lag_min']:.2f} periods, {100 * x['late']:.1f} % > 1 late, "
              f"{100 * x['early']:.1f} % > 1 early; held lag p95 {x['held_p95']:.2f}, max {x['held_max']:.2f}; "
              f"{x['main_swaps']} main-window compositions, {x['m_renders']} manifold renders; "
              f"CPU {x['cpu_ms']:.1f} ms per frame shown", flush=True)
        print(f"      clock started {x['press_ms']:.1f} ms after Play was pressed, the first new frame on screen "
              f"{x['first_move_ms']:.1f} ms after it; stages (median ms): chosen->render {x['queue_med']:.1f}, "
              f"render {x['render_med']:.1f} "
              f"(max {x['render_max']:.1f}), render->swap {x['compose_med']:.1f}, chosen->swap {x['latency_med']:.1f}; "
              f"timer late p95 {x['timer_late_p95']:.1f}, max {x['timer_late_max']:.1f} ms; GUI thread waited "
              f"{x['run_wait']:.0f} ms for a core between choice and swap "
              f"(helpers + X server {x['helper_wait']:.0f} ms); {len(x['gcs'])} collections "
              f"({', '.join(f'gen {g} {1e3 * (b - a):.1f} ms' for a, b, g in x['gcs'][:6])})")
        print("      late frames by cause: " + ", ".join(f"{c} {n}" for c, n in x["causes"].items())
              + "; per late frame, ms (GUI thread waited for a core / rasteriser thread + X server waited / "
              "GUI CPU / chosen->swap / look-ahead): "
              + " ".join(f"{w:.0f}/{h:.0f}/{c:.0f}/{d:.0f}/{la:.0f}" for w, h, c, d, la in x["late_wait_cpu"][:10])
              + "; steal on the GUI thread's core per late frame, ms: "
              + " ".join(f"{v:.0f}" for v in x["steal_late"][:10]), flush=True)
        print(f"      GUI thread CPU choice->swap (its clock) median {x['thread_cpu_med']:.1f} ms, p99 "
              f"{x['thread_cpu_p99']:.1f} ms; steal on all cores during the playback {1e3 * x['steal_s']:.0f} ms; "
              f"long frames (GUI CPU > {1e3 * LONG_FRAME_CPU_S:.0f} ms): {len(x['longs'])}", flush=True)
        for lf in x["longs"]:
            print(_long_line(lf), flush=True)

    def mm(key, scale=1.0, fmt=".2f"):
        v = [scale * x[key] for x in res]
        return f"min {min(v):{fmt}}, median {np.median(v):{fmt}}, max {max(v):{fmt}}"

    print(f"frames/s shown:               {mm('fps', fmt='.1f')} (goal >= 30)")
    print(f"lag max (frame periods):      {mm('lag_max')} (goal <= 1)")
    print(f"lag p99 (frame periods):      {mm('lag_p99')}")
    print(f"lag p95 (frame periods):      {mm('lag_p95')}")
    print(f"lag median (frame periods):   {mm('lag_med')}")
    print(f"% frames > 1 period late:     {mm('late', 100, '.1f')}")
    print(f"CPU per frame shown (ms):     {mm('cpu_ms', fmt='.1f')}")
    print(f"Play -> first new frame (ms): {mm('first_move_ms', fmt='.1f')}")
    total = {c: sum(x["causes"][c] for x in res) for c in CAUSES}
    print("late frames by cause (all repeats): " + ", ".join(f"{c} {n}" for c, n in total.items()))
    longs = [lf for x in res for lf in x["longs"]]
    n_steal = sum(lf["steal_explains"] for lf in longs)
    print(f"long frames (GUI thread CPU > {1e3 * LONG_FRAME_CPU_S:.0f} ms between choice and swap): {len(longs)} in "
          f"{len(res)} playbacks, {sum(x['frames'] for x in res)} frames; steal on their core covers the excess CPU "
          f"in {n_steal}, not in {len(longs) - n_steal} (counting steal up to the next tick after the swap: in "
          f"{sum(lf['steal_next_explains'] for lf in longs)})" + (
              "; own CPU " + ", ".join(f"{1e3 * lf['cpu']:.0f}" for lf in longs) + " ms, steal on their core "
              + ", ".join(f"{1e3 * lf['steal']:.0f}" for lf in longs) + " ms" if longs else ""))
    print(f"steal on all cores per playback (ms): {mm('steal_s', 1e3, '.0f')} (/proc/stat, 10-ms steps)")
    print(f"load average during repeats:  {mm('load', fmt='.1f')}")
    # asked for only now: querying the GL capabilities of a shown widget made the window
    # compose ~13 times a second more for the rest of the process (measured)
    print(f"OpenGL renderer: {gb.gl_renderer(lips)}")
    print(f"wall {time.perf_counter() - t_all:.1f} s; peak RSS {gb.peak_rss_mb():.0f} MiB; "
          f"load average {os.getloadavg()[0]:.1f} at end")
    if probe is not None:
        _probe_report(probe, res)
    for key, label, unit in (("fps", "frames/s shown", "/s"), ("lag_max", "worst lag", "periods"),
                             ("late", "share of frames > 1 period late", "1"), ("cpu_ms", "CPU per frame shown", "ms")):
        bench.figure(label, [x[key] for x in res], unit, first_is_separate=True, cold=True, show=False,
                     headline=key in ("fps", "lag_max"), peak_rss_mib=gb.peak_rss_mb())
    bench.finish()
    print("SUMMARY " + json.dumps({"n_frames": int(m.Fy_.shape[0]), "rss_mb": gb.peak_rss_mb(),
                                   "repeats": [{k: float(x[k]) for k in ("fps", "lag_max", "late", "cpu_ms", "load")}
                                               for x in res]}))
    win.close()


def side_by_side(args, specs, cap) -> None:
    """Each manifold in fresh processes, alternating; the frame rates and lags side by side."""
    bench = Harness("bench_gui_playback", args)
    gb.header(f"playback in the lip view, side by side: {', '.join(gb.spec_label(s) for s in specs)}")
    runs = {spec: [] for spec in specs}
    for spec in gb.order_of_runs(specs, args.rounds):
        cmd = [sys.executable, os.path.abspath(__file__), "--manifold", spec, "--repeats", str(args.repeats),
               "--max-seconds", str(args.max_seconds), "--preset", args.preset, "--no-history", *cap]
        r = gb.run_marked_child(cmd, spec, "SUMMARY")
        runs[spec].append(r)
        fps = ", ".join(f"{x['fps']:.1f}" for x in r["repeats"])
        lags = ", ".join(f"{x['lag_max']:.2f}" for x in r["repeats"])
        print(f"   [{gb.spec_label(spec)}] {r['n_frames']:,} frames: frames/s per repeat {fps} (repeat 1 cold); "
              f"worst lag {lags} periods; peak RSS {r['rss_mb']:.0f} MiB", flush=True)
    for key, label, unit, scale in (("fps", "frames/s shown", "/s", 1.0), ("lag_max", "worst lag", "periods", 1.0),
                                    ("late", "frames > 1 period late", "%", 100.0),
                                    ("cpu_ms", "CPU per frame shown", "ms", 1.0)):
        gb.compare(label, {s: [x[key] for r in rs for x in r["repeats"]] for s, rs in runs.items()}, unit, scale,
                   bench=bench, headline=key in ("fps", "lag_max"))
    loads = [x["load"] for rs in runs.values() for r in rs for x in r["repeats"]]
    print(f"   load average during repeats {min(loads):.1f}-{max(loads):.1f}")
    bench.finish()


if __name__ == "__main__":
    main()

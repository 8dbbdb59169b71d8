"""Soak benchmark: drive the real explorer window for minutes and watch it stay alive.

Usage (needs a display; on a headless machine use Xvfb)::

    xvfb-run -a -s "-screen 0 1600x1200x24" python tools/soak_explorer.py [--minutes 10]
        [--preset default|small|paper] [--text "bob meets mum"] [--click-every 2] [--json out.json]

The script is a monitor: it starts the explorer in a child process (this file with
``--child``) and samples the child's resident set size (``VmRSS`` from /proc) every
``--sample`` seconds, so a crash of the child (an abort such as ``Fatal Python error:
none_dealloc``, a segfault, an exception) is seen and reported with its exit status
instead of taking the measurement down with it.

The child does what a user does, on Qt timers inside the real event loop:

* loads the synthetic talker ``--preset`` through File › Open's worker path (the
  user cache is used as ``lipspace explore`` uses it),
* types ``--text`` into the trajectory editor and synthesises it, then plays the
  synthetic trajectory on a loop (playback restarts as soon as it stops),
* every ``--click-every`` seconds clicks a random frame of the manifold view with a real
  mouse event (falling back to VTK's picker if the VTK build drops synthetic clicks),
* every 5 s switches panels (clusters/scree tabs), colour mode and hemisphere,
* every ``--resynth-every`` s (30; 0 = never) loads another input (an utterance or the
  typed text) and synthesises it again, alternating methods, in the worker thread,
* autosaves as ``lipspace explore`` does (:mod:`app.files.autosave`, into a temporary
  directory; ``--no-autosave`` to leave it out).

Printed at the end: whether the child was alive when the soak time ran out and how it
exited; frames played (playback events) and frames/s; clicks; syntheses; panel
switches; ``sys.getrefcount(None)`` at start and end in the child (a drop means a Qt
binding is losing references to None, the PySide6 6.12.0 / CPython 3.11 crash); RSS at
launch, after loading and the first synthesis (start), at the end, its maximum and its
least-squares slope in MB/min over the soak (also over its second half, and after the
first ``--warmup`` seconds, where first-click allocations are settled); wall time and
the BLAS kernel (threadpoolctl).

``--tracemalloc N`` traces Python allocations in the child (N frames per traceback;
this slows the child): the memory Python objects hold is sampled with the RSS, so the
two growths over the same stretch of the soak can be told apart (Python-side vs native:
Qt, VTK, OpenGL, the allocator), and the ``--top`` source lines whose Python allocations
grew most between the end of the warm-up and the end of the soak are printed.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

SAMPLE_S = 5.0
PANEL_EVERY_S = 5.0


def rss_mb(pid: int) -> float | None:
    """Resident set size of process ``pid`` in MB (None once it has gone)."""
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except (FileNotFoundError, ProcessLookupError):
        return None
    return None


def slope_mb_per_min(ts, values) -> float:
    """Least-squares slope of ``values`` (MB) against ``ts`` (s), in MB/min (nan with < 2 samples)."""
    import numpy as np

    t = np.asarray(ts, np.float64)
    v = np.asarray(values, np.float64)
    if len(t) < 2 or np.ptp(t) == 0:
        return float("nan")
    return float(np.polyfit(t / 60.0, v, 1)[0])


# ============================================================================ child: the window
def _say(**kw) -> None:
    print(json.dumps(kw), flush=True)


def traced() -> dict:
    """The memory Python allocations hold now (tracemalloc), in MB; empty when not tracing."""
    import tracemalloc

    if not tracemalloc.is_tracing():
        return {}
    return {"py_mb": tracemalloc.get_traced_memory()[0] / 2**20}


def child(args) -> int:
    import random

    import numpy as np
    from PySide6 import QtCore, QtTest, QtWidgets

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    from app.main_window import MainWindow
    from app.scene import pick_display_point

    try:
        from threadpoolctl import threadpool_info

        blas = ", ".join(f"{i.get('internal_api')} {i.get('version')} {i.get('architecture')} "
                         f"{i.get('num_threads')} threads" for i in threadpool_info() if i.get("user_api") == "blas")
    except ImportError:
        blas = "threadpoolctl not installed"
    none_start = sys.getrefcount(None)
    if args.tracemalloc:
        import tracemalloc

        tracemalloc.start(args.tracemalloc)
    rng = random.Random(args.seed)
    autosaver = None
    if args.autosave:
        import tempfile

        from app.files.autosave import Autosaver

        autosaver = Autosaver(Path(tempfile.mkdtemp(prefix="lipspace-soak-state-")))
        autosaver.begin()
    win = MainWindow(autosave=autosaver)
    win.resize(1400, 900)
    win.show()
    app.processEvents()
    t0 = time.perf_counter()
    runner = win.open_source(None, preset=args.preset)
    runner.wait()
    if runner.state != "done":
        _say(event="error", message=f"loading the {args.preset} talker ended {runner.state}: {runner.error}")
        return 2
    s, ed, view = win.state, win.editor, win.manifold_view
    _say(event="loaded", seconds=time.perf_counter() - t0, frames=int(s.n_frames), blas=blas,
         python=sys.version.split()[0], none_start=none_start)

    counts = {"frames": 0, "clicks": 0, "clicks_selected": 0, "picker_fallbacks": 0, "synths": 0,
              "synth_failures": 0, "switches": 0, "restarts": 0}
    s.events.playback.connect(lambda k: counts.__setitem__("frames", counts["frames"] + (k is not None)))
    soaking = {"on": True, "synth_busy": False}
    methods = [ed.method_box.itemData(i) for i in range(ed.method_box.count())]
    if not methods:
        _say(event="error", message="no synthesis method available in the editor")
        return 2

    def restart_playback(on):
        if not on and soaking["on"] and not soaking["synth_busy"] and s.n_playback > 0:
            counts["restarts"] += 1
            QtCore.QTimer.singleShot(0, lambda: s.set_playing(True) if soaking["on"] else None)

    s.events.playing.connect(restart_playback)

    def synthesise(source: str):
        """Load an input and synthesise it in the worker; playback restarts when it is done."""
        soaking["synth_busy"] = True
        ed.set_method(methods[counts["synths"] % len(methods)])
        if source == "utterance":
            ed.set_source("utterance")
            ed.utt_box.setCurrentIndex(rng.randrange(ed.utt_box.count()))
            ok = ed.load()
        else:
            ok = ed.set_text(args.text, source="text")
        r = ed.synthesize() if ok else None
        if r is None:
            counts["synth_failures"] += 1
            soaking["synth_busy"] = False
            return

        def finished(*_a):
            counts["synths"] += r.state == "done"
            counts["synth_failures"] += r.state != "done"
            soaking["synth_busy"] = False
            if soaking["on"]:
                s.set_playing(True)

        for sig in (r.finished, r.failed, r.cancelled):
            sig.connect(finished)

    Y = np.asarray(s.manifold.Fy_[:, :3], np.float64)
    widget = view.plotter.interactor

    def click():
        i = rng.randrange(len(Y))
        x, y = pick_display_point(view.plotter, Y[i])
        ratio = widget.devicePixelRatioF()
        height = view.plotter.render_window.GetSize()[1]
        before = counts_frame_events[0]
        pos = QtCore.QPoint(int(round(x / ratio)), int(round((height - 1 - y) / ratio)))
        QtTest.QTest.mouseClick(widget, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                                pos)
        if counts_frame_events[0] == before and view.picker is not None:
            counts["picker_fallbacks"] += 1
            view.picker.pick(x, y)
        counts["clicks"] += 1
        counts["clicks_selected"] += counts_frame_events[0] != before

    counts_frame_events = [0]
    s.events.frame.connect(lambda _f: counts_frame_events.__setitem__(0, counts_frame_events[0] + 1))

    def switch_panels():
        tab = ("scree", "clusters")[counts["switches"] % 2]
        win.docks[tab].raise_()
        s.set_hemisphere(("future", "past")[counts["switches"] % 2])
        if counts["switches"] % 3 == 2:
            s.set_color_mode(("density", "class", "phone")[(counts["switches"] // 3) % 3])
        counts["switches"] += 1

    synthesise("text")
    t_soak = time.perf_counter()
    _say(event="soak_start", rss_mb=rss_mb(os.getpid()), none=sys.getrefcount(None), **traced())
    last = {"click": t_soak, "panel": t_soak, "synth": t_soak, "sample": t_soak}
    snaps = {}

    def step():
        now = time.perf_counter()
        if now - t_soak >= args.minutes * 60.0:
            finish()
            return
        if now - last["click"] >= args.click_every:
            last["click"] = now
            click()
        if now - last["panel"] >= PANEL_EVERY_S:
            last["panel"] = now
            switch_panels()
        if args.resynth_every > 0 and now - last["synth"] >= args.resynth_every and not soaking["synth_busy"]:
            last["synth"] = now
            synthesise(("utterance", "text")[counts["synths"] % 2])
        if now - last["sample"] >= SAMPLE_S:
            last["sample"] = now
            _say(event="sample", t=now - t_soak, none=sys.getrefcount(None), rss_mb=rss_mb(os.getpid()),
                 **traced(), **autosaves(), **counts)
        if args.tracemalloc and "warm" not in snaps and now - t_soak >= args.warmup:
            import tracemalloc

            snaps["warm"] = (now - t_soak, tracemalloc.take_snapshot())

    def autosaves():
        if autosaver is None:
            return {"autosaves": None, "autosave_error": None}
        return {"autosaves": autosaver.saves, "autosave_error": autosaver.last_error}

    def finish():
        soaking["on"] = False
        ticker.stop()
        s.set_playing(False)
        if args.tracemalloc and "warm" in snaps:
            import tracemalloc

            t_warm, first = snaps["warm"]
            stats = tracemalloc.take_snapshot().compare_to(first, "lineno")
            _say(event="tracemalloc", t_from=t_warm, t_to=time.perf_counter() - t_soak,
                 top=[{"where": str(st.traceback[0]), "size_diff_kb": st.size_diff / 1024,
                       "count_diff": st.count_diff, "size_kb": st.size / 1024} for st in stats[:args.top]])
        _say(event="soak_end", t=time.perf_counter() - t_soak, alive=True, none=sys.getrefcount(None),
             **autosaves(), **counts)
        win.close()
        if autosaver is not None:
            autosaver.finish()
        app.quit()

    ticker = QtCore.QTimer()
    ticker.timeout.connect(step)
    ticker.start(100)
    app.exec()
    _say(event="closed", none_end=sys.getrefcount(None))
    return 0


# ============================================================================ parent: the monitor
def monitor(args) -> int:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", "--minutes", str(args.minutes), "--preset",
           args.preset, "--text", args.text, "--click-every", str(args.click_every), "--seed", str(args.seed),
           "--resynth-every", str(args.resynth_every), "--autosave" if args.autosave else "--no-autosave",
           "--warmup", str(args.warmup), "--tracemalloc", str(args.tracemalloc), "--top", str(args.top)]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=str(ROOT))
    events: list[dict] = []
    err_tail: list[str] = []

    def read_out():
        for line in proc.stdout:
            try:
                events.append(json.loads(line))
            except json.JSONDecodeError:
                err_tail.append(line.rstrip())

    def read_err():
        for line in proc.stderr:
            err_tail.append(line.rstrip())
            del err_tail[:-40]

    threads = [threading.Thread(target=f, daemon=True) for f in (read_out, read_err)]
    for t in threads:
        t.start()
    samples: list[tuple[float, float, str]] = []  # (wall s, rss MB, phase)
    deadline = t0 + args.minutes * 60.0 + args.load_timeout
    timed_out = False
    while proc.poll() is None:
        r = rss_mb(proc.pid)
        phase = "soak" if any(e.get("event") == "soak_start" for e in events) else "load"
        if any(e.get("event") == "soak_end" for e in events):
            phase = "end"
        if r is not None:
            samples.append((time.perf_counter() - t0, r, phase))
        if time.perf_counter() > deadline:
            timed_out = True
            proc.kill()
            break
        time.sleep(args.sample)
    rc = proc.wait()
    for t in threads:
        t.join(5)
    wall = time.perf_counter() - t0

    by = {e.get("event"): e for e in events}
    soak = [(t, r) for t, r, ph in samples if ph == "soak"]
    warm = [(t, r) for t, r in soak if t - soak[0][0] >= args.warmup]
    loaded, end = by.get("loaded", {}), by.get("soak_end") or (
        [e for e in events if e.get("event") == "sample"] or [{}])[-1]
    summary = {
        "preset": args.preset, "minutes": args.minutes, "python": loaded.get("python"),
        "blas": loaded.get("blas"), "wall_s": wall, "load_s": loaded.get("seconds"),
        "alive_at_end": bool(by.get("soak_end", {}).get("alive")), "exit_code": rc, "timed_out": timed_out,
        "frames_played": end.get("frames", 0), "soak_s": end.get("t"),
        "clicks": end.get("clicks", 0), "clicks_selected": end.get("clicks_selected", 0),
        "picker_fallbacks": end.get("picker_fallbacks", 0), "synths": end.get("synths", 0),
        "synth_failures": end.get("synth_failures", 0), "panel_switches": end.get("switches", 0),
        "playback_restarts": end.get("restarts", 0), "autosaves": end.get("autosaves"),
        "autosave_error": end.get("autosave_error"),
        "none_refcount_start": loaded.get("none_start"), "none_refcount_end": end.get("none"),
        "rss_launch_mb": samples[0][1] if samples else None,
        "rss_start_mb": soak[0][1] if soak else None, "rss_end_mb": soak[-1][1] if soak else None,
        "rss_max_mb": max((r for _t, r, _p in samples), default=None),
        "rss_slope_mb_per_min": slope_mb_per_min(*zip(*soak)) if len(soak) > 1 else float("nan"),
        "rss_slope_second_half_mb_per_min": (slope_mb_per_min(*zip(*soak[len(soak) // 2:]))
                                             if len(soak) > 3 else float("nan")),
        "warmup_s": args.warmup, "rss_after_warmup_mb": warm[0][1] if warm else None,
        "rss_slope_after_warmup_mb_per_min": slope_mb_per_min(*zip(*warm)) if len(warm) > 1 else float("nan"),
        "rss_samples": len(soak),
        "rss_trace": [[round(t, 1), round(r, 1)] for t, r in soak],
        "resynth_every_s": args.resynth_every, "click_every_s": args.click_every,
    }
    traced_samples = [(e["t"], e["rss_mb"], e["py_mb"]) for e in events
                      if e.get("event") == "sample" and "py_mb" in e and e.get("rss_mb") is not None]
    warm_traced = [x for x in traced_samples if x[0] >= args.warmup]
    if len(warm_traced) > 1:
        t_w, rss_w, py_w = zip(*warm_traced)
        summary.update({"py_traced_after_warmup_mb": [py_w[0], py_w[-1]],
                        "py_traced_slope_after_warmup_mb_per_min": slope_mb_per_min(t_w, py_w),
                        "rss_in_child_slope_after_warmup_mb_per_min": slope_mb_per_min(t_w, rss_w),
                        "tracemalloc_top": by.get("tracemalloc", {}).get("top", [])})
    fps = summary["frames_played"] / summary["soak_s"] if summary["soak_s"] else float("nan")
    print(f"soak_explorer: preset {args.preset}, {args.minutes:g} min soak, Python {summary['python']}, "
          f"BLAS {summary['blas']}, load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"  wall {wall:.1f} s; load {summary['load_s'] or float('nan'):.1f} s; soak {summary['soak_s'] or 0:.1f} s")
    print(f"  alive at end of soak: {'yes' if summary['alive_at_end'] else 'NO'}; exit code {rc}"
          + (" (killed after the time-out)" if timed_out else ""))
    print(f"  frames played {summary['frames_played']} ({fps:.1f}/s); clicks {summary['clicks']} "
          f"({summary['clicks_selected']} selected a frame, {summary['picker_fallbacks']} via the VTK picker "
          f"fallback); syntheses {summary['synths']} ({summary['synth_failures']} failed); panel switches "
          f"{summary['panel_switches']}; playback restarts {summary['playback_restarts']}; autosaves "
          f"{summary['autosaves']}"
          + (f" (last error: {summary['autosave_error']})" if summary['autosave_error'] else ""))
    print(f"  sys.getrefcount(None) in the child: {summary['none_refcount_start']} at start -> "
          f"{summary['none_refcount_end']} at the end of the soak")
    if soak:
        print(f"  RSS MB: launch {summary['rss_launch_mb']:.1f}, start {summary['rss_start_mb']:.1f}, "
              f"end {summary['rss_end_mb']:.1f}, max {summary['rss_max_mb']:.1f}; slope "
              f"{summary['rss_slope_mb_per_min']:+.2f} MB/min (second half "
              f"{summary['rss_slope_second_half_mb_per_min']:+.2f}) over {len(soak)} samples")
    if len(warm) > 1:
        print(f"  after the first {args.warmup:g} s of soak (first clicks, recolour buffers, caches): RSS "
              f"{summary['rss_after_warmup_mb']:.1f} -> {summary['rss_end_mb']:.1f} MB, slope "
              f"{summary['rss_slope_after_warmup_mb_per_min']:+.2f} MB/min")
    if "py_traced_slope_after_warmup_mb_per_min" in summary:
        a, b = summary["py_traced_after_warmup_mb"]
        print(f"  tracemalloc ({args.tracemalloc} frames), after the warm-up: "
              f"Python objects hold {a:.1f} -> {b:.1f} MB, "
              f"slope {summary['py_traced_slope_after_warmup_mb_per_min']:+.2f} MB/min; RSS (same samples) "
              f"{summary['rss_in_child_slope_after_warmup_mb_per_min']:+.2f} MB/min; the rest is native")
        for st in summary["tracemalloc_top"]:
            print(f"    {st['size_diff_kb']:+9.1f} kB ({st['count_diff']:+d} blocks, now {st['size_kb']:.1f} kB)  "
                  f"{st['where']}")
    if rc != 0 or not summary["alive_at_end"]:
        print("  child stderr (tail):", *err_tail[-20:], sep="\n    ")
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    return 0 if (rc == 0 and summary["alive_at_end"]) else 1


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--minutes", type=float, default=10.0, help="soak length after warm-up (default %(default)s)")
    p.add_argument("--preset", choices=("small", "default", "paper"), default="default",
                   help="synthetic talker to load (default %(default)s)")
    p.add_argument("--text", default="bob meets mum in the warm room", help="text typed into the editor")
    p.add_argument("--click-every", type=float, default=2.0, help="seconds between clicks (default %(default)s)")
    p.add_argument("--resynth-every", type=float, default=30.0,
                   help="seconds between new syntheses, 0 = only the first (default %(default)s)")
    p.add_argument("--sample", type=float, default=SAMPLE_S, help="RSS sampling period, s (default %(default)s)")
    p.add_argument("--load-timeout", type=float, default=900.0,
                   help="seconds allowed for loading/building before the soak (default %(default)s)")
    p.add_argument("--warmup", type=float, default=60.0,
                   help="seconds of soak left out of the after-warm-up RSS slope (default %(default)s)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--autosave", action=argparse.BooleanOptionalAction, default=True,
                   help="autosave the session as the explorer does (default: on)")
    p.add_argument("--json", default=None, help="also write the summary here")
    p.add_argument("--tracemalloc", type=int, default=0, metavar="N",
                   help="trace Python allocations with N frames per traceback (0 = off, the default)")
    p.add_argument("--top", type=int, default=12, help="source lines listed with --tracemalloc (default %(default)s)")
    p.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.minutes <= 0:
        p.error(f"--minutes must be > 0, got {args.minutes}")
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        print("soak_explorer: no display; run under xvfb-run -a -s '-screen 0 1600x1200x24'", file=sys.stderr)
        return 3
    return child(args) if args.child else monitor(args)


if __name__ == "__main__":
    sys.exit(main())

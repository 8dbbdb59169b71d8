"""Benchmark: start-up of the explorer — time to an interactive window, and to the manifold shown.

Usage: python benchmarks/bench_gui_startup.py [--cold 1] [--warm 3] [--preset default]

Each run is a fresh process executing what ``lipspace explore`` / ``make run`` executes
(``app.main_window.launch`` on the synthetic talker), under an X server (re-runs itself
under ``xvfb-run`` without one; software OpenGL), with its own autosave state dir.

* cold: an empty ``LIPSPACE_CACHE_DIR`` (the synthetic corpus and its manifold are built:
  the first ``make run`` on a new machine);
* warm: the same cache again (the cached manifold is loaded).

Measured from just before the process is started:

* window interactive: the main window is on screen and its event loop answers (a 20-ms
  probe timer in the GUI thread runs), with the process's CPU time until then (less
  sensitive than wall time to other work on a shared machine);
* manifold shown: the manifold has reached the window and the manifold view has put its
  first frame with it on screen;
* event-loop stalls: the longest gap between probe ticks while the manifold is loading
  in the worker (what a user clicking around would feel) and around showing it;
* how long a modal dialog blocked the window while the manifold loaded; the summary's
  "window usable" is the later of "interactive" and the moment such a dialog went away.

Also printed: each loading stage and when it began (cold run). Goals (issue 9 item 6):
window interactive in under 20 s cold and under 5 s warm.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _gui_bench as gb  # noqa: E402


def child(t0: float, preset: str) -> None:
    """One start-up, timed against ``t0`` (time.time() in the parent before the process started)."""
    from PySide6 import QtCore, QtWidgets

    app = QtWidgets.QApplication(sys.argv[:1])
    out = {"imports_done": time.time() - t0, "window": None, "interactive": None, "manifold": None, "shown": None,
           "stall_loading": 0.0, "stall_showing": 0.0, "stages": []}
    probe = {"last": None, "win": None, "swap_after": None}

    def on_swap():
        if out["manifold"] is not None and out["shown"] is None:
            out["shown"] = time.time() - t0

    def tick():
        now = time.time()
        gap = 0.0 if probe["last"] is None else now - probe["last"]
        probe["last"] = now
        from app.main_window import MainWindow

        win = probe["win"]
        if win is None:
            wins = [w for w in app.topLevelWidgets() if isinstance(w, MainWindow)]
            if wins and wins[0].isVisible():
                win = probe["win"] = wins[0]
                out["window"] = now - t0
                win.manifold_view.plotter.interactor.frameSwapped.connect(on_swap)
            return
        if out["interactive"] is None:
            out["interactive"] = now - t0  # first probe tick with the window on screen: the loop answers
            out["cpu_interactive"] = time.process_time()  # this process's CPU until then (all threads)
            return
        if out["manifold"] is None:
            if QtWidgets.QApplication.activeModalWidget() is not None:  # e.g. a modal progress dialog
                out["modal_s"] = out.get("modal_s", 0.0) + gap
                probe["modal"] = True
            elif probe.get("modal"):
                probe["modal"] = False
                out["modal_closed"] = now - t0
            if gap > out["stall_loading"]:
                out["stall_loading"], out["stall_loading_at"] = gap, now - t0
            if win.state.manifold is not None:
                out["manifold"] = now - t0
                if probe.get("modal"):
                    out["modal_closed"] = now - t0
        elif out["shown"] is None or now - t0 < out["shown"] + 1.0:
            out["stall_showing"] = max(out["stall_showing"], gap)
        else:
            from app.views.task_progress import TaskProgress

            prog = win.findChild(TaskProgress, "task_progress")
            if prog is not None:
                out["stages"] = [(name, t - prog.stages[0][1]) for name, t in prog.stages]
            out["rss_mb"] = gb.peak_rss_mb()
            out["gl"] = gb.gl_renderer(win.manifold_view.plotter)
            win.close()
            app.quit()

    timer = QtCore.QTimer()
    timer.setInterval(20)
    timer.timeout.connect(tick)
    timer.start()
    from app.main_window import launch

    launch(None, preset=preset, restore=False)
    print("RESULT " + json.dumps(out))


def run_one(preset: str, cache: str, state: str) -> dict:
    env = dict(os.environ, LIPSPACE_CACHE_DIR=cache, LIPSPACE_STATE_DIR=state)
    t0 = time.time()
    p = subprocess.run([sys.executable, __file__, "--child", repr(t0), "--preset", preset], capture_output=True,
                       text=True, env=env, timeout=1800)
    line = [ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")]
    if p.returncode != 0 or not line:
        sys.exit(f"start-up run failed ({p.returncode}):\n{p.stdout[-2000:]}\n{p.stderr[-3000:]}")
    r = json.loads(line[0][7:])
    r["wall"] = time.time() - t0
    return r


def show(kind: str, k: int, r: dict) -> None:
    print(f"   {kind} {k}: window on screen {r['window']:.2f} s, interactive {r['interactive']:.2f} s "
          f"(process CPU {r.get('cpu_interactive', float('nan')):.2f} s until then), "
          f"manifold in the window {r['manifold']:.2f} s, drawn {r['shown']:.2f} s; longest event-loop stall "
          f"while loading {1e3 * r['stall_loading']:.0f} ms (ending at {r.get('stall_loading_at', 0):.2f} s), around showing it {1e3 * r['stall_showing']:.0f} ms; "
          f"window blocked by a modal dialog for {r.get('modal_s', 0.0):.1f} s of the load; "
          f"peak RSS {r.get('rss_mb', 0):.0f} MiB", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cold", type=int, default=1, help="runs with an empty cache (each builds the talker)")
    ap.add_argument("--warm", type=int, default=3, help="runs with the cache filled")
    ap.add_argument("--preset", default="default")
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    gb.ensure_display()
    if args.child is not None:
        child(float(args.child), args.preset)
        return
    import numpy as np

    gb.header(f"start-up of the explorer on the synthetic talker '{args.preset}' (fresh process per run)")
    t_all = time.perf_counter()
    runs = {"cold": [], "warm": []}
    with tempfile.TemporaryDirectory(prefix="lipspace-bench-") as tmp:
        state = os.path.join(tmp, "state")
        for k in range(args.cold):
            cache = os.path.join(tmp, f"cache{k}")  # empty
            r = run_one(args.preset, cache, state)
            runs["cold"].append(r)
            show("cold", k + 1, r)
            if k == 0:
                print("      stages (s after the load started): " + ", ".join(
                    f"{name} {t:.1f}" for name, t in r["stages"]))
        cache = os.path.join(tmp, "cache0")
        if not runs["cold"]:
            os.makedirs(cache, exist_ok=True)
            run_one(args.preset, cache, state)  # fill the cache
        for k in range(args.warm):
            r = run_one(args.preset, cache, state)
            runs["warm"].append(r)
            show("warm", k + 1, r)
    for kind, goal in (("cold", 20.0), ("warm", 5.0)):
        rs = runs[kind]
        if not rs:
            continue
        # usable: interactive, or, when a modal dialog blocked the window, the moment it went away
        inter = [max(r["interactive"], r.get("modal_closed", 0.0)) for r in rs]
        shown = [r["shown"] for r in rs]
        print(f"{kind}: window usable (interactive, no modal dialog) min {min(inter):.2f} s, median {np.median(inter):.2f} s (goal < {goal:g} s); "
              f"manifold drawn min {min(shown):.2f} s, median {np.median(shown):.2f} s (n={len(rs)})")
    print(f"   OpenGL renderer: {(runs['warm'] or runs['cold'])[0].get('gl')}; wall {time.perf_counter() - t_all:.0f} s; "
          f"load average {os.getloadavg()[0]:.1f} at end")


if __name__ == "__main__":
    main()

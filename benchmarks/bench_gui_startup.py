"""Benchmark: start-up of the explorer — time to an interactive window, and to the manifold shown.

Usage: python benchmarks/bench_gui_startup.py [--cold 1] [--warm 3] [--preset default]
       [--manifold FILE|talker ...]

Each run is a fresh process executing what ``lipspace explore`` / ``make run`` executes
(``app.launching.launch`` on the synthetic talker, or on a manifold file given with
``--manifold``: any size, blocked corpora included; ``talker`` names the default talker,
so several can be measured side by side, alternating), under an X server (re-runs itself
under ``xvfb-run`` without one; software OpenGL), with its own autosave state dir.

* cold: for the talker an empty ``LIPSPACE_CACHE_DIR`` (the synthetic corpus and its
  manifold are built: the first ``make run`` on a new machine); for a manifold file the
  file, and the blocked corpus it references, dropped from the system's file cache first
  (``posix_fadvise(DONTNEED)``: read from disk);
* warm: the same cache again (the cached manifold is loaded), the files in the file cache.

Measured from just before the process is started:

* window interactive: the main window is on screen and its event loop answers (a 20-ms
  probe timer in the GUI thread runs), with the process's CPU time until then (less
  sensitive than wall time to other work on a shared machine);
* manifold shown: the manifold has reached the window and the manifold view has put its
  first frame with it on screen — from then on a click selects (**usable** for a large
  manifold);
* event-loop stalls: the longest gap between probe ticks while the manifold is loading
  in the worker (what a user clicking around would feel) and around showing it;
* how long a modal dialog blocked the window while the manifold loaded; the summary's
  "window usable" is the later of "interactive" and the moment such a dialog went away;
* the process's peak resident memory (VmHWM) once the manifold is shown.

Also printed: each loading stage and when it began (cold run). Goals: window interactive
in under 20 s cold and under 5 s warm (issue 9 item 6); the manifold of 1M frames shown
in under 10 s warm with a peak under 4 GiB, 10M frames in under 30 s and 8 GiB (issue 29);
the talker usable in 10 s cold and 2.5 s warm on a quiet machine (issue 41).

**Floor.** Before every run a fresh process runs ``python -c "import PySide6.QtWidgets,
pyvista"`` (what any window of this kind pays before it can draw) and its wall time is
printed beside the run's; the summary gives min / median of the floor and of each run's
"usable" divided by the floor just before it (``--no-floor`` leaves it out). The machine's
load average and the BLAS setting are printed at start and after every run.
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
from _harness import Harness  # noqa: E402


def child(t0: float, preset: str, path=None) -> None:
    """One start-up, timed against ``t0`` (time.time() in the parent before the process started)."""
    from PySide6 import QtCore, QtWidgets

    app = QtWidgets.QApplication(sys.argv[:1])
    out = {"imports_done": time.time() - t0, "window": None, "interactive": None, "manifold": None, "shown": None,
           "stall_loading": 0.0, "stall_showing": 0.0, "stages": []}
    probe = {"last": None, "win": None, "swap_after": None}

    def on_swap():
        if out["manifold"] is not None and out["shown"] is None:
            out["shown"] = time.time() - t0
            out["cpu_shown"] = time.process_time()  # this process's CPU until usable (all threads)

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
            out["load"] = os.getloadavg()[0]
            out["gl"] = gb.gl_renderer(win.manifold_view.plotter)
            win.close()
            app.quit()

    timer = QtCore.QTimer()
    timer.setInterval(20)
    timer.timeout.connect(tick)
    timer.start()
    from app.launching import launch

    launch(path, preset=preset, restore=False)
    print("RESULT " + json.dumps(out), flush=True)
    from app.workers import exit_if_tasks_run

    exit_if_tasks_run(0)  # as `lipspace explore` leaves a task still inside an engine step


FLOOR_CODE = "import PySide6.QtWidgets, pyvista"


def _child_cpu() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_floor() -> tuple[float, float]:
    """(wall s, CPU s) of a fresh process that only imports Qt's widgets and pyvista."""
    t0, c0 = time.time(), _child_cpu()
    p = subprocess.run([sys.executable, "-c", FLOOR_CODE], capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        sys.exit(f"floor run failed ({p.returncode}): {p.stderr[-2000:]}")
    return time.time() - t0, _child_cpu() - c0


def usable(r: dict) -> float:
    """The run's "usable": the manifold drawn, or later when a modal dialog blocked the window longer."""
    return max(r["shown"], r.get("modal_closed", 0.0))


def run_one(preset: str, cache: str, state: str, path=None, cap=()) -> dict:
    env = dict(os.environ, LIPSPACE_CACHE_DIR=cache, LIPSPACE_STATE_DIR=state)
    t0 = time.time()
    extra = ["--child-path", path] if path else []
    p = subprocess.run([sys.executable, __file__, "--child", repr(t0), "--preset", preset, *extra, *cap],
                       capture_output=True, text=True, env=env, timeout=1800)
    line = [ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")]
    if p.returncode != 0 or not line:
        sys.exit(f"start-up run failed ({p.returncode}):\n{p.stdout[-2000:]}\n{p.stderr[-3000:]}")
    r = json.loads(line[0][7:])
    r["wall"] = time.time() - t0
    return r


def manifold_files(path) -> list[str]:
    """The manifold file and, when it references a blocked corpus, that corpus and its block files."""
    import glob

    import numpy as np

    files = [path]
    with np.load(path) as z:
        if "corpus_blocks_source" in z.files:
            src = str(z["corpus_blocks_source"])
            rel = str(z["corpus_blocks_relative"]) if "corpus_blocks_relative" in z.files else ""
            cand = os.path.join(os.path.dirname(path), rel) if rel else src
            src = cand if os.path.isfile(cand) else src
            files += [src] + sorted(glob.glob(os.path.join(src[:-len(".npz")] + ".blocks", "*.npy")))
    return files


def drop_from_file_cache(files) -> None:
    """Ask the system to drop ``files`` from its page cache (the next read comes from disk)."""
    for f in files:
        fd = os.open(f, os.O_RDONLY)
        try:
            os.fsync(fd)
            os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
        finally:
            os.close(fd)


def read_into_file_cache(files) -> None:
    for f in files:
        with open(f, "rb") as fh:
            while fh.read(1 << 24):
                pass


def show(kind: str, k: int, r: dict, label: str = "") -> None:
    tag = f" [{label}]" if label else ""
    print(f"   {kind} {k}{tag}: window on screen {r['window']:.2f} s, interactive {r['interactive']:.2f} s "
          f"(process CPU {r.get('cpu_interactive', float('nan')):.2f} s until then), "
          f"manifold in the window {r['manifold']:.2f} s, drawn {r['shown']:.2f} s; longest event-loop stall "
          f"while loading {1e3 * r['stall_loading']:.0f} ms (ending at {r.get('stall_loading_at', 0):.2f} s), "
          f"around showing it {1e3 * r['stall_showing']:.0f} ms; "
          f"window blocked by a modal dialog for {r.get('modal_s', 0.0):.1f} s of the load; "
          f"peak RSS {r.get('rss_mb', 0):.0f} MiB; load average {r.get('load', float('nan')):.1f}", flush=True)


def environment_notes(compile_first: bool) -> None:
    """Print what else a start pays in this environment: bytecode of Lipspace's own modules, pandas."""
    import importlib.util
    from pathlib import Path

    import app
    import engine

    roots = [Path(engine.__file__).parent, Path(app.__file__).parent]
    if compile_first:
        import compileall

        for r in roots:
            compileall.compile_dir(str(r), quiet=1)
    mods = [f for r in roots for f in r.rglob("*.py")]
    cached = sum(1 for f in mods if importlib.util.cache_from_source(str(f)) and
                 Path(importlib.util.cache_from_source(str(f))).is_file())
    print(f"   Lipspace from {roots[0].parent}; bytecode cached for {cached} of {len(mods)} of its modules"
          f"{' (compiled first: --compile)' if compile_first else ''}; PYTHONDONTWRITEBYTECODE="
          f"{os.environ.get('PYTHONDONTWRITEBYTECODE', 'unset')}")
    has_pandas = importlib.util.find_spec("pandas") is not None
    why = " (scikit-learn imports it, and pyarrow with it, at every start: the [test] extra)" if has_pandas else ""
    print(f"   pandas {'installed' if has_pandas else 'not installed'}{why}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cold", type=int, default=1, help="runs with an empty cache (each builds the talker) / with "
                                                        "the manifold's files dropped from the file cache")
    ap.add_argument("--warm", type=int, default=3, help="runs with the cache filled / the files in the file cache")
    ap.add_argument("--compile", action="store_true",
                    help="byte-compile the checkout's engine/ and app/ first (what pip does for an installed "
                         "package; PYTHONDONTWRITEBYTECODE otherwise leaves every start compiling them)")
    ap.add_argument("--no-floor", dest="floor", action="store_false",
                    help=f"leave out the floor process ({FLOOR_CODE!r}) run before every start-up")
    ap.add_argument("--child-path", default=None, help=argparse.SUPPRESS)
    Harness.add_arguments(ap)
    args, cap = gb.parse_bench_args(ap)
    if args.child is not None:
        child(float(args.child), args.preset, args.child_path)
        return
    import numpy as np

    bench = Harness("bench_gui_startup", args, quiet=True)  # its own table below; the record for the history

    specs = gb.manifold_specs(args)
    gb.header(f"start-up of the explorer on {', '.join(gb.spec_label(s) for s in specs)} (fresh process per run)")
    environment_notes(args.compile)
    t_all = time.perf_counter()
    runs = {spec: {"cold": [], "warm": []} for spec in specs}
    with tempfile.TemporaryDirectory(prefix="lipspace-bench-") as tmp:
        state = os.path.join(tmp, "state")
        talker_cache = os.path.join(tmp, "cache0")

        def one(spec, kind, k):
            floor, floor_cpu = run_floor() if args.floor else (None, None)
            if spec == gb.TALKER:
                cache = os.path.join(tmp, f"cache{k}") if kind == "cold" else talker_cache
                if kind == "warm" and not os.path.isdir(cache):
                    os.makedirs(cache, exist_ok=True)
                    run_one(args.preset, cache, state, cap=cap)  # fill the cache
                r = run_one(args.preset, cache, state, cap=cap)
            else:
                files = manifold_files(spec)
                (drop_from_file_cache if kind == "cold" else read_into_file_cache)(files)
                r = run_one(args.preset, talker_cache, state, path=spec, cap=cap)
            r["floor"], r["floor_cpu"] = floor, floor_cpu
            runs[spec][kind].append(r)
            show(kind, len(runs[spec][kind]), r, gb.spec_label(spec) if len(specs) > 1 else "")
            if floor is not None:
                print(f"      floor just before ({FLOOR_CODE!r}): {floor:.2f} s wall, {floor_cpu:.2f} s CPU; usable / "
                      f"floor {usable(r) / floor:.2f} (wall), {r.get('cpu_shown', float('nan')) / floor_cpu:.2f} "
                      f"(CPU: {r.get('cpu_shown', float('nan')):.2f} s until usable)", flush=True)
            if kind == "cold" and len(runs[spec]["cold"]) == 1:
                print("      stages (s after the load started): " + ", ".join(
                    f"{name} {t:.1f}" for name, t in r["stages"]))

        for k, spec in enumerate(gb.order_of_runs(specs, args.cold)):
            one(spec, "cold", k)
        for k, spec in enumerate(gb.order_of_runs(specs, args.warm)):
            one(spec, "warm", k)
    for spec in specs:
        for kind, goal in (("cold", 20.0), ("warm", 5.0)):
            rs = runs[spec][kind]
            if not rs:
                continue
            # usable: interactive, or, when a modal dialog blocked the window, the moment it went away
            inter = [max(r["interactive"], r.get("modal_closed", 0.0)) for r in rs]
            shown = [r["shown"] for r in rs]
            rss = [r.get("rss_mb", 0.0) for r in rs]
            print(f"{kind} [{gb.spec_label(spec)}]: window interactive (no modal dialog) min {min(inter):.2f} s, "
                  f"median {np.median(inter):.2f} s (goal < {goal:g} s); "
                  f"manifold drawn (usable) min {min(shown):.2f} s, "
                  f"median {np.median(shown):.2f} s; peak RSS max {max(rss):.0f} MiB (n={len(rs)})")
            label = gb.spec_label(spec)
            bench.figure(f"window usable, {kind} [{label}]", [usable(r) for r in rs], cold=kind == "cold",
                         peak_rss_mib=max(rss) or None, headline=True, show=False)
            floors = [r["floor"] for r in rs if r.get("floor")]
            if floors:
                ratios = [usable(r) / r["floor"] for r in rs if r.get("floor")]
                cpu = [r["cpu_shown"] / r["floor_cpu"] for r in rs if r.get("floor_cpu") and r.get("cpu_shown")]
                bench.figure(f"floor ({FLOOR_CODE}), {kind} [{label}]", floors, cold=True, show=False)
                bench.figure(f"window usable / floor, {kind} [{label}]", ratios, unit="x", cold=kind == "cold",
                             headline=True, show=False)
                if cpu:
                    bench.figure(f"CPU until usable / floor CPU, {kind} [{label}]", cpu, unit="x",
                                 cold=kind == "cold", show=False)
                print(f"   {kind} [{gb.spec_label(spec)}]: floor ({FLOOR_CODE!r}) min {min(floors):.2f} s, median "
                      f"{np.median(floors):.2f} s; usable / floor min {min(ratios):.2f}, median {np.median(ratios):.2f}"
                      + (f"; CPU until usable / the floor's CPU min {min(cpu):.2f}, median {np.median(cpu):.2f}"
                         if cpu else "") + "; "
                      f"load average during the runs {min(r.get('load', 0) for r in rs):.1f}-"
                      f"{max(r.get('load', 0) for r in rs):.1f}")
    if len(specs) > 1:
        print("side by side (ratios against the first):")
        for kind in ("cold", "warm"):
            gb.compare(f"{kind}: manifold drawn", {s: [r["shown"] for r in runs[s][kind]] for s in specs}, "s", 1.0)
    first = next(r for s in specs for k in ("warm", "cold") for r in runs[s][k])
    print(f"   OpenGL renderer: {first.get('gl')}; wall {time.perf_counter() - t_all:.0f} s; "
          f"load average {os.getloadavg()[0]:.1f} at end")
    bench.fact(gl_renderer=first.get("gl"), stages_cold=next((r["stages"] for s in specs for r in runs[s]["cold"]), []))
    rec = bench.finish()
    print(f"(record {'appended to ' + str(bench.history) if bench.history else 'not kept'}; "
          f"load {rec['load']['min1']:.1f}-{rec['load']['max1']:.1f}; BLAS of the parent only)")


if __name__ == "__main__":
    main()

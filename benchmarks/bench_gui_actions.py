"""Benchmark: cluster ellipsoids, the phone filter and the trajectory editor in the real window, at any size.

Usage: python benchmarks/bench_gui_actions.py [--repeats 5] [--rounds 1] [--manifold FILE|talker ...]

Drives ``app.main_window.MainWindow`` under an X server (re-runs itself under
``xvfb-run`` without one; software OpenGL) on each manifold given (``talker``: the
default synthetic talker; files: any built manifold, blocked corpora included), each in
fresh processes, alternating (``--rounds``). After a click has selected a state, each
action is done as the user does it and timed from the action until the manifold view's
frame showing its result has reached the screen (its widget's ``frameSwapped`` after a
render that followed the action), ``--repeats`` times:

* ellipsoid on / off: ticking a phone in the clusters panel (the 2-s.d. ellipsoid and its
  member points drawn), unticking it;
* phone filter: colour by phone, then a filter typed into the view's phone box (``p b m``,
  ``aa``, ...: the points recoloured);
* utterance loaded: the editor's input set to an utterance and Load pressed (targets on the
  timeline, the utterance's trajectory drawn);
* state added: "Add clicked state" (Ctrl+T) in the editor (the timeline redrawn; the time
  until the event loop is idle, as nothing changes in the 3-D view);
* synthesised: Synthesise with the manifold method and with linear interpolation (a worker
  runs it; the time until the synthetic trajectory is drawn), the first and the later ones.

Prints min / median per action and manifold and the ratios against the first manifold,
with the process's peak RSS and the load average. Goal (issue 29 item 4): each under
150 ms at 1M frames; nothing computes an N x N matrix or loops over frames in Python.
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


def until_drawn(app, view, log, action, timeout=120.0):
    """Seconds from ``action()`` until a manifold-view frame rendered after it is on screen."""
    n_r, n_s = len(log.renders), len(log.swaps)
    t0 = time.perf_counter()
    action()
    end = t0 + timeout
    while time.perf_counter() < end:
        app.processEvents()
        if len(log.renders) > n_r and any(s > log.renders[n_r] for s in log.swaps[n_s:]):
            return next(s for s in log.swaps[n_s:] if s > log.renders[n_r]) - t0
        time.sleep(0.0005)
    raise RuntimeError(f"nothing was drawn within {timeout} s")


def until_idle(app, action) -> float:
    """Seconds from ``action()`` until Qt has handled the events it posted (a widget repaint)."""
    t0 = time.perf_counter()
    action()
    app.processEvents()
    return time.perf_counter() - t0


def run(spec: str, repeats: int, preset: str) -> dict:
    import numpy as np
    from PySide6 import QtCore

    m, src = gb.load_manifold(spec, preset)
    app, win = gb.open_window(m, src)
    s, view, ed = win.state, win.manifold_view, win.editor
    log = gb.RenderLog(view.plotter)
    out = {k: [] for k in ("ellipsoid on", "ellipsoid off", "phone filter", "utterance loaded", "state added",
                           "synthesised (manifold, first)", "synthesised (manifold)", "synthesised (linear)")}
    cam = np.asarray(view.plotter.camera.position, np.float32)
    frame = int(np.argmin(np.linalg.norm(np.asarray(m.Fy_[:, :3], np.float32) - cam, axis=1)))
    until_drawn(app, view, log, lambda: s.select_frame(frame))
    rows = sorted(s.cluster_rows(), key=lambda r: -r["count"])
    phones = [r["phone"] for r in rows[:repeats]]
    for ph in phones:
        item = win.clusters.table.findItems(ph, QtCore.Qt.MatchFlag.MatchExactly)[0]
        out["ellipsoid on"].append(until_drawn(app, view, log,
                                               lambda item=item: item.setCheckState(QtCore.Qt.CheckState.Checked)))
        out["ellipsoid off"].append(until_drawn(app, view, log,
                                                lambda item=item: item.setCheckState(QtCore.Qt.CheckState.Unchecked)))
    until_drawn(app, view, log, lambda: view.color_box.setCurrentIndex(view.color_box.findData("phone")))
    names = list(s.phone_names)
    filters = [" ".join(names[k:k + 3]) for k in range(0, 3 * repeats, 3)]
    for text in filters:
        def typed(text=text):
            view.phone_edit.setText(text)
            view.phone_edit.editingFinished.emit()
        out["phone filter"].append(until_drawn(app, view, log, typed))
    ed.set_source("utterance")
    for k in range(repeats):
        ed.utt_box.setCurrentIndex((k * 7919) % ed.utt_box.count())
        out["utterance loaded"].append(until_drawn(app, view, log, ed.load))
        s.select_frame(frame)
        gb.settle(app, 0.2)
        out["state added"].append(until_idle(app, ed.add_selected_state))
    for method, key in (("manifold", "synthesised (manifold)"), ("linear", "synthesised (linear)")):
        ed.set_method(method)
        for k in range(repeats):
            def synth():
                ed.synthesize()
            t = until_drawn(app, view, log, synth, timeout=1800.0)
            while ed._runner is not None and ed._runner.state == "running":
                app.processEvents()
            if s.synthetic is None:
                raise RuntimeError(f"synthesis with {method} gave nothing: {ed.readout.text()}")
            (out["synthesised (manifold, first)"] if method == "manifold" and k == 0 else out[key]).append(t)
    res = {"spec": spec, "n_frames": int(m.Fy_.shape[0]), "times": out, "rss_mb": gb.peak_rss_mb(),
           "load": os.getloadavg()[0]}
    win.close()
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="times each action is done in a process")
    ap.add_argument("--rounds", type=int, default=1, help="fresh processes per manifold")
    Harness.add_arguments(ap)
    args, cap = gb.parse_bench_args(ap)
    if args.child is not None:
        print("RESULT " + json.dumps(run(args.child, args.repeats, args.preset)))
        return
    bench = Harness("bench_gui_actions", args)
    specs = gb.manifold_specs(args)
    gb.header("ellipsoids, phone filter, trajectory editor (real window)")
    t_all = time.perf_counter()
    runs = {spec: [] for spec in specs}
    for spec in gb.order_of_runs(specs, args.rounds):
        r = gb.run_marked_child([sys.executable, __file__, "--child", spec, "--repeats", args.repeats, "--preset",
                                 args.preset, *cap], spec)
        runs[spec].append(r)
        print(f"   run [{gb.spec_label(spec)}]: {r['n_frames']:,} frames, peak RSS {r['rss_mb']:.0f} MiB, "
              f"load {r['load']:.1f}", flush=True)
    for action in next(iter(runs.values()))[0]["times"]:
        gb.compare(action, {sp: [t for r in rs for t in r["times"][action]] for sp, rs in runs.items()}, bench=bench,
                   headline=action in ("ellipsoid on", "phone filter"),
                   peak_rss_mib=max(r["rss_mb"] for rs in runs.values() for r in rs))
    print(f"wall {time.perf_counter() - t_all:.1f} s")
    bench.finish()


if __name__ == "__main__":
    main()

"""Benchmark: click a point -> its hemisphere drawn, in the real explorer window.

Usage: python benchmarks/bench_gui_click.py [--clicks 21] [--repeats 3] [--preset default]
       [--manifold FILE|talker ...] [--sound off|on|compare]

Drives ``app.main_window.MainWindow`` on the default synthetic talker (28,800 frames), or
on the manifold files given with ``--manifold`` (any size, blocked corpora included;
``talker`` names the default talker, so e.g. ``--manifold talker m1m.npz`` measures both
side by side), under an X server (re-runs itself under ``xvfb-run`` without one; software
OpenGL). Every run is a fresh process, the manifolds alternating (``--repeats`` runs
each). Each click is a real mouse press/release on the manifold view's VTK widget
(QTest) at the screen position of a frame near the camera, each in a different state.
Measured per click: wall time from the press until the manifold view's frame with the
new hop-distance colours has reached the screen (the widget's ``frameSwapped`` after the
render that follows the click), the process's CPU time over the same span (all threads,
the software rasteriser's included: less sensitive to other processes on a shared
machine than wall time), and how many VTK renders the click caused in the manifold
view and in the lip view. Each click's selection is checked against a search over
every frame of the manifold (drawn or not: above ``app.models.lod.DEFAULT_MAX_POINTS`` frames the view
draws groups of frames): the selected frame must be the one under the cursor (``app.models.picking.
frame_under_cursor`` over all N frames projected by the view's camera).

* cold: the first click in a fresh process (window just opened);
* warm: ``--clicks`` further clicks in the same process.

``--sound on`` first loads an utterance with audio into the trajectory editor and waits
until its waveform and spectrogram are drawn under the timeline; ``--sound compare``
does that too and then alternates the warm clicks between the sound shown and hidden
(the editor's Sound box; the editor dock kept at the same height, so the manifold view
has the same size either way), printing both and the ratio shown / hidden per pair.

Prints min / median / max, the ratios against the first manifold, peak RSS, BLAS kernel
and the OpenGL renderer. Goals: median under 150 ms (issue 9 item 5; at 1M frames,
issue 29 item 2), under 300 ms at 10M frames.
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


def click_targets(win, n):
    """Frames to click: near the camera (never hidden), each in a new state, far apart in the list."""
    import numpy as np

    m, view = win.state.manifold, win.manifold_view
    Y = np.asarray(m.Fy_[:, :3], np.float32)
    cam = np.asarray(view.plotter.camera.position, np.float32)
    order = np.argsort(np.linalg.norm(Y - cam, axis=1))
    labels = m.states_.labels_
    out, seen = [], set()
    for i in order[:4000]:
        if int(labels[i]) not in seen:
            seen.add(int(labels[i]))
            out.append(int(i))
        if len(out) == n:
            break
    return out


def click_once(app, win, frame, mlog, llog, timeout=20.0):
    """One real mouse click on ``frame``'s point; returns (seconds to frame on screen, renders, lip renders)."""
    from PySide6 import QtCore
    from PySide6.QtTest import QTest

    from app.scene import pick_display_point

    view = win.manifold_view
    widget = view.plotter.interactor
    x, y = pick_display_point(view.plotter, win.state.manifold.Fy_[frame, :3])
    ratio = widget.devicePixelRatioF()
    height = view.plotter.render_window.GetSize()[1]
    pos = QtCore.QPoint(int(round(x / ratio)), int(round((height - 1 - y) / ratio)))
    mouse = (pos.x() * ratio, height - 1 - pos.y() * ratio)  # where VTK sees the click (display pixels)
    from app.scene.projection import view_transform

    camera = view_transform(view.plotter)  # what the click is seen through (a first click may re-lay the window out)
    n_r, n_s, n_l = len(mlog.renders), len(mlog.swaps), len(llog.renders)
    before = win.state.state
    c0 = time.process_time()
    t0 = time.perf_counter()
    QTest.mouseClick(widget, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, pos)
    # wait for the first frame that reached the screen after a render that followed the click
    end = t0 + timeout
    while time.perf_counter() < end:
        app.processEvents()
        if len(mlog.renders) > n_r and any(s > mlog.renders[n_r] for s in mlog.swaps[n_s:]):
            break
        time.sleep(0.0005)
    else:
        raise RuntimeError(f"no frame reached the screen within {timeout} s of clicking frame {frame}")
    shown = next(s for s in mlog.swaps[n_s:] if s > mlog.renders[n_r])
    cpu = time.process_time() - c0  # this process's CPU (all threads, llvmpipe's included) until then
    # where the time went: until the render starts (state update, events, picking), the render, the rest
    # (lip view render and Qt composing the window)
    parts = (mlog.starts[n_r] - t0, mlog.renders[n_r] - mlog.starts[n_r], shown - mlog.renders[n_r])
    gb.settle(app, 0.4)  # let any further (redundant) renders of this click happen, to count them
    s = win.state
    if s.state == before or s.frame is None or s.color_mode != "distance":
        raise RuntimeError(f"the click on frame {frame} did not select a new state (state {s.state})")
    return shown - t0, len(mlog.renders) - n_r, len(llog.renders) - n_l, parts, cpu, mouse, camera


def frame_under_cursor_everywhere(win, mouse, camera):
    """The frame under ``mouse`` by a search over every frame of the manifold (the check of a click)."""
    import numpy as np

    from app.models.picking import frame_under_cursor
    from app.scene.projection import project

    view = win.manifold_view
    M, size = camera
    Fy = win.state.manifold.Fy_
    best, loc = [], view.locator
    for a in range(0, Fy.shape[0], 1 << 20):  # blocks of frames: bounded memory at any N
        xy, depth = project(np.asarray(Fy[a:a + (1 << 20), :3], np.float64), M, size)
        i = frame_under_cursor(xy, depth, mouse, dot_radius=loc.dot_radius, radius=loc.radius)
        if i is not None:
            best.append((a + i, xy[i], depth[i]))
    if not best:
        return None
    idx = np.array([b[0] for b in best])
    xy = np.array([b[1] for b in best])
    depth = np.array([b[2] for b in best])
    i = frame_under_cursor(xy, depth, mouse, dot_radius=loc.dot_radius, radius=loc.radius)
    return None if i is None else int(idx[i])


def show_sound(app, win, timeout=60.0) -> dict:
    """Load the first utterance with audio into the editor; wait until its spectrogram is drawn."""
    from PySide6 import QtCore

    ed = win.editor
    m = win.state.manifold
    uid = next((u.id for u in m.corpus_.utterances if ed.sound_track.audio_path(u.id) is not None), None)
    if uid is None:
        sys.exit("--sound: no utterance of this corpus has audio (the synthetic talker needs espeak-ng)")
    ed.set_source("utterance")
    ed.utt_box.setCurrentIndex(ed.utt_box.findData(uid))
    t0 = time.perf_counter()
    ed.load()
    while ed.sound.shown_at is None:
        app.processEvents()
        time.sleep(0.001)
        if time.perf_counter() - t0 > timeout:
            sys.exit(f"the spectrogram of {uid} was not drawn within {timeout} s ({ed.sound_track.error})")
    shown = ed.sound.shown_at - t0
    gb.settle(app, 0.3)
    dock = win.docks["editor"]
    win.resizeDocks([dock], [dock.height()], QtCore.Qt.Orientation.Vertical)  # the same height without the sound
    spec = ed.sound.display.spectrogram
    return {"utterance": uid, "shown_s": shown, "seconds": ed.sound.display.duration,
            "spectrogram": list(spec.power_db.shape), "dock_h": dock.height()}


def run_clicks(n_clicks: int, spec: str, preset: str, sound: str = "off") -> dict:
    """One fresh process: open the window on ``spec``, click 1 + ``n_clicks`` times, check every selection."""
    from PySide6 import QtCore

    load0 = os.getloadavg()[0]
    t = time.perf_counter()
    m, src = gb.load_manifold(spec, preset)
    loaded = time.perf_counter() - t
    t = time.perf_counter()
    app, win = gb.open_window(m, src)
    opened = time.perf_counter() - t
    snd = show_sound(app, win) if sound != "off" else None
    mlog, llog = gb.RenderLog(win.manifold_view.plotter), gb.RenderLog(win.lip_view.plotter)
    frames = click_targets(win, n_clicks + 1)
    res, checks, shown = [], [], []
    for k, f in enumerate(frames):
        if sound == "compare" and k > 0:  # warm clicks alternate: sound shown, hidden, shown, ...
            on = k % 2 == 1
            win.editor.sound_box.setChecked(on)
            win.resizeDocks([win.docks["editor"]], [snd["dock_h"]], QtCore.Qt.Orientation.Vertical)
            gb.settle(app, 0.3)
            if win.editor.sound.isVisible() != on:
                raise RuntimeError(f"the sound panel did not {'show' if on else 'hide'}")
            shown.append(on)
        r = click_once(app, win, f, mlog, llog)
        res.append(r[:5])
        want = frame_under_cursor_everywhere(win, r[5], r[6])
        checks.append({"target": f, "selected": win.state.frame, "under_cursor": want,
                       "candidates": win.manifold_view.locator.n_candidates})
    out = {"spec": spec, "n_frames": int(m.Fy_.shape[0]), "n_points": int(win.state.cloud.n_points),
           "first": res[0], "warm": res[1:], "checks": checks, "load_s": loaded, "window_s": opened,
           "gl": gb.gl_renderer(win.manifold_view.plotter),
           "size": list(win.manifold_view.plotter.render_window.GetSize()),
           "rss_mb": gb.peak_rss_mb(), "load": (load0 + os.getloadavg()[0]) / 2, "sound": snd, "shown": shown}
    win.close()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clicks", type=int, default=21, help="warm clicks in each process")
    ap.add_argument("--repeats", type=int, default=3, help="fresh processes per manifold (each: 1 cold click)")
    ap.add_argument("--sound", choices=("off", "on", "compare"), default="off",
                    help="the editor's waveform and spectrogram: not loaded, shown, or shown / hidden by turns")
    Harness.add_arguments(ap)
    args, cap = gb.parse_bench_args(ap)
    if args.child is not None:  # one fresh process: print its clicks as JSON
        print("RESULT " + json.dumps(run_clicks(args.clicks, args.child, args.preset, args.sound)))
        return
    import numpy as np

    bench = Harness("bench_gui_click", args)
    specs = gb.manifold_specs(args)
    gb.header("click -> hemisphere drawn (real window, real mouse clicks)")
    t_all = time.perf_counter()
    runs = {spec: [] for spec in specs}
    for spec in gb.order_of_runs(specs, args.repeats):
        r = gb.run_marked_child([sys.executable, __file__, "--child", spec, "--clicks", args.clicks, "--preset",
                                 args.preset, "--sound", args.sound, *cap], spec)
        runs[spec].append(r)
        ok = sum(c["selected"] == c["under_cursor"] for c in r["checks"])
        print(f"   run [{gb.spec_label(spec)}] {len(runs[spec])}: {r['n_frames']:,} frames ({r['n_points']:,} drawn), "
              f"loaded {r['load_s']:.1f} s, window {r['window_s']:.2f} s; first click {1e3 * r['first'][0]:.1f} ms, "
              f"warm median {1e3 * np.median([w[0] for w in r['warm']]):.1f} ms; selection = frame under the "
              f"cursor among all frames {ok}/{len(r['checks'])}; peak RSS {r['rss_mb']:.0f} MiB; "
              f"load {r['load']:.1f}", flush=True)
    first = next(iter(runs.values()))[0]
    print(f"   OpenGL renderer: {first['gl']}; window {gb.WINDOW_SIZE[0]}x{gb.WINDOW_SIZE[1]}, "
          f"manifold view {first['size'][0]}x{first['size'][1]} px")
    for spec, rs in runs.items():
        cold = [r["first"] for r in rs]
        warm = [w for r in rs for w in r["warm"]]
        checks = [c for r in rs for c in r["checks"]]
        print(f"[{gb.spec_label(spec)}] {rs[0]['n_frames']:,} frames, {rs[0]['n_points']:,} drawn points")
        print(f"   cold (first click in a fresh process, {len(cold)} processes): {gb.stats([c[0] for c in cold])}")
        peak = max(r["rss_mb"] for r in rs)
        bench.figure(f"click -> hemisphere drawn, cold [{gb.spec_label(spec)}]", [c[0] for c in cold], cold=True,
                     headline=True, show=False, peak_rss_mib=peak)
        bench.figure(f"click -> hemisphere drawn, warm [{gb.spec_label(spec)}]", [c[0] for c in warm], cold=False,
                     headline=True, show=False, peak_rss_mib=peak, cpu_median_s=float(np.median([c[4] for c in warm])))
        print(f"   warm ({len(warm)} clicks): {gb.stats([c[0] for c in warm])}; CPU of the process per click "
              f"{gb.stats([c[4] for c in warm])}")
        print(f"   renders per click: manifold view {sorted(set(c[1] for c in cold + warm))}, "
              f"lip view {sorted(set(c[2] for c in cold + warm))}")
        for k, what in enumerate(("until the render starts (state update, picking)", "manifold view render",
                                  "after it until on screen (lip render, window composition)")):
            print(f"   warm, {what}: {gb.stats([c[3][k] for c in warm])}")
        ok = sum(c["selected"] == c["under_cursor"] for c in checks)
        own = sum(c["selected"] == c["target"] for c in checks)
        bench.fact(**{f"picks exact [{gb.spec_label(spec)}]": [ok, len(checks)]})
        print(f"   picking: the selected frame is the one under the cursor among all {rs[0]['n_frames']:,} frames in "
              f"{ok} of {len(checks)} clicks (the clicked target itself in {own}); frames searched per click "
              f"median {np.median([c['candidates'] for c in checks]):.0f}")
        rss = ", ".join(f"{r['rss_mb']:.0f}" for r in rs)
        loads = ", ".join(f"{r['load_s']:.1f}" for r in rs)
        print(f"   peak RSS {rss} MiB; manifold loaded and prepared in {loads} s")
        if rs[0]["sound"]:
            sd = rs[0]["sound"]
            print(f"   sound: utterance {sd['utterance']} ({sd['seconds']:.2f} s of audio), spectrogram "
                  f"{sd['spectrogram'][0]} bands x {sd['spectrogram'][1]} frames drawn {1e3 * sd['shown_s']:.0f} ms "
                  f"after Load; editor dock {sd['dock_h']} px high (cold clicks: with the sound shown)")
        pairs_of = [(w, k) for r in rs for w, k in zip(r["warm"], r["shown"])]
        if pairs_of:
            on = [w for w, k in pairs_of if k]
            off = [w for w, k in pairs_of if not k]
            n = min(len(on), len(off))
            wall = np.asarray([w[0] for w in on[:n]]) / np.asarray([w[0] for w in off[:n]])
            cpu = np.asarray([w[4] for w in on[:n]]) / np.asarray([w[4] for w in off[:n]])
            print(f"   warm, sound shown:  {gb.stats([w[0] for w in on])}; CPU {gb.stats([w[4] for w in on])}")
            print(f"   warm, sound hidden: {gb.stats([w[0] for w in off])}; CPU {gb.stats([w[4] for w in off])}")
            print(f"   ratio shown / hidden, click by click in turn: wall min {wall.min():.2f}, median "
                  f"{np.median(wall):.2f}, max {wall.max():.2f}; CPU median {np.median(cpu):.2f} (n={n})")
    if len(runs) > 1:
        print("side by side (fresh processes alternating; ratios against the first manifold):")
        gb.compare("cold click", {s: [r["first"][0] for r in rs] for s, rs in runs.items()})
        gb.compare("warm click", {s: [w[0] for r in rs for w in r["warm"]] for s, rs in runs.items()})
        gb.compare("warm click CPU", {s: [w[4] for r in rs for w in r["warm"]] for s, rs in runs.items()})
    print(f"wall {time.perf_counter() - t_all:.1f} s")
    bench.finish()


if __name__ == "__main__":
    main()

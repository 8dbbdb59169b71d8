"""Benchmark: click a point -> its hemisphere drawn, in the real explorer window.

Usage: python benchmarks/bench_gui_click.py [--clicks 21] [--cold 3] [--preset default] [--sound off|on|compare]

Drives ``app.main_window.MainWindow`` on the default synthetic talker (28,800 frames)
under an X server (re-runs itself under ``xvfb-run`` without one; software OpenGL).
Each click is a real mouse press/release on the manifold view's VTK widget (QTest) at
the screen position of a point near the camera, each in a different state. Measured
per click: wall time from the press until the manifold view's frame with the new
hop-distance colours has reached the screen (the widget's ``frameSwapped`` after the
render that follows the click), the process's CPU time over the same span (all threads,
the software rasteriser's included: less sensitive to other processes on a shared
machine than wall time), and how many VTK renders the click caused in the manifold
view and in the lip view.

* cold: the first click in a fresh process (window just opened), ``--cold`` processes;
* warm: ``--clicks`` further clicks in one process.

``--sound on`` first loads an utterance with audio into the trajectory editor and waits
until its waveform and spectrogram are drawn under the timeline; ``--sound compare``
does that too and then alternates the warm clicks between the sound shown and hidden
(the editor's Sound box; the editor dock kept at the same height, so the manifold view
has the same size either way), printing both and the ratio shown / hidden per pair.

Prints min / median / max, peak RSS, BLAS kernel and the OpenGL renderer.
Goal (issue 9 item 5): median under 150 ms.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _gui_bench as gb  # noqa: E402


def click_targets(win, n):
    """Frames to click: near the camera (never hidden), each in a new state, far apart in the list."""
    import numpy as np

    m, view = win.state.manifold, win.manifold_view
    Y = np.asarray(m.Fy_[:, :3], np.float64)
    cam = np.asarray(view.plotter.camera.position)
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
    return shown - t0, len(mlog.renders) - n_r, len(llog.renders) - n_l, parts, cpu


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


def run_clicks(n_clicks: int, preset: str, sound: str = "off") -> dict:
    from PySide6 import QtCore

    m, src = gb.default_manifold(preset)
    t = time.perf_counter()
    app, win = gb.open_window(m, src)
    opened = time.perf_counter() - t
    snd = show_sound(app, win) if sound != "off" else None
    mlog, llog = gb.RenderLog(win.manifold_view.plotter), gb.RenderLog(win.lip_view.plotter)
    frames = click_targets(win, n_clicks + 1)
    res, shown = [], []
    for k, f in enumerate(frames):
        if sound == "compare" and k > 0:  # warm clicks alternate: sound shown, hidden, shown, ...
            on = k % 2 == 1
            win.editor.sound_box.setChecked(on)
            win.resizeDocks([win.docks["editor"]], [snd["dock_h"]], QtCore.Qt.Orientation.Vertical)
            gb.settle(app, 0.3)
            if win.editor.sound.isVisible() != on:
                raise RuntimeError(f"the sound panel did not {'show' if on else 'hide'}")
            shown.append(on)
        res.append(click_once(app, win, f, mlog, llog))
    out = {"first": res[0], "warm": res[1:], "window_s": opened, "gl": gb.gl_renderer(win.manifold_view.plotter),
           "size": list(win.manifold_view.plotter.render_window.GetSize()), "rss_mb": gb.peak_rss_mb(),
           "sound": snd, "shown": shown}
    win.close()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clicks", type=int, default=21, help="warm clicks in one process")
    ap.add_argument("--cold", type=int, default=3, help="fresh processes for the cold first click")
    ap.add_argument("--preset", default="default")
    ap.add_argument("--sound", choices=("off", "on", "compare"), default="off",
                    help="the editor's waveform and spectrogram: not loaded, shown, or shown / hidden by turns")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    gb.ensure_display()
    if args.child:  # one fresh process: print the first click as JSON
        r = run_clicks(0, args.preset, "on" if args.sound != "off" else "off")
        print("RESULT " + json.dumps({"first": r["first"][:3]}))
        return
    gb.header("click -> hemisphere drawn (real window, real mouse clicks)")
    t_all = time.perf_counter()
    r = run_clicks(args.clicks, args.preset, args.sound)
    print(f"   OpenGL renderer: {r['gl']}; window {gb.WINDOW_SIZE[0]}x{gb.WINDOW_SIZE[1]}, "
          f"manifold view {r['size'][0]}x{r['size'][1]} px; window opened in {r['window_s']:.2f} s")
    if r["sound"]:
        s = r["sound"]
        print(f"   sound: utterance {s['utterance']} ({s['seconds']:.2f} s of audio), spectrogram "
              f"{s['spectrogram'][0]} bands x {s['spectrogram'][1]} frames drawn {1e3 * s['shown_s']:.0f} ms after "
              f"Load; editor dock {s['dock_h']} px high (cold clicks: with the sound shown)")
    cold = [r["first"]]
    for _ in range(max(0, args.cold - 1)):
        p = subprocess.run([sys.executable, __file__, "--child", "--preset", args.preset, "--sound", args.sound],
                           capture_output=True, text=True, env=os.environ)
        line = [ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")]
        if p.returncode != 0 or not line:
            sys.exit(f"cold child failed ({p.returncode}):\n{p.stderr[-2000:]}")
        cold.append(json.loads(line[0][7:])["first"])
    warm = r["warm"]
    print(f"cold (first click in a fresh process, {len(cold)} processes): {gb.stats([c[0] for c in cold])}")
    print(f"   renders per cold click: manifold view {[c[1] for c in cold]}, lip view {[c[2] for c in cold]}")
    print(f"warm ({len(warm)} clicks):                           {gb.stats([c[0] for c in warm])}")
    print(f"   renders per warm click: manifold view {sorted(set(c[1] for c in warm))}, "
          f"lip view {sorted(set(c[2] for c in warm))}")
    print(f"   warm, CPU time of the process per click (less sensitive to other load): "
          f"{gb.stats([c[4] for c in warm])}")
    if r["shown"]:
        import numpy as np

        on = [c[0] for c, k in zip(warm, r["shown"]) if k]
        off = [c[0] for c, k in zip(warm, r["shown"]) if not k]
        pairs = np.asarray(on[:len(off)]) / np.asarray(off[:len(on)])
        cpu_on = [c[4] for c, k in zip(warm, r["shown"]) if k]
        cpu_off = [c[4] for c, k in zip(warm, r["shown"]) if not k]
        cpu_pairs = np.asarray(cpu_on[:len(cpu_off)]) / np.asarray(cpu_off[:len(cpu_on)])
        print(f"   warm, sound shown:  {gb.stats(on)}; CPU {gb.stats(cpu_on)}")
        print(f"   warm, sound hidden: {gb.stats(off)}; CPU {gb.stats(cpu_off)}")
        print(f"   ratio shown / hidden, click by click in turn: wall min {pairs.min():.2f}, median "
              f"{np.median(pairs):.2f}, max {pairs.max():.2f}; CPU median {np.median(cpu_pairs):.2f} "
              f"(n={pairs.size})")
    for k, what in enumerate(("until the render starts (state update, picking)", "manifold view render",
                              "after it until on screen (lip render, window composition)")):
        print(f"   warm, {what}: {gb.stats([c[3][k] for c in warm])}")
    print(f"wall {time.perf_counter() - t_all:.1f} s; peak RSS {r['rss_mb']:.0f} MiB; "
          f"load average {os.getloadavg()[0]:.1f} at end")


if __name__ == "__main__":
    main()

"""Benchmark: video import (FaceMesh tracking + head-pose removal) frames per second and peak memory.

Usage: python benchmarks/bench_video_import.py [--seconds 20 60] [--repeats 3] [--size 512] [--keep DIR] [--live]

Makes a 30 fps video of scikit-image's astronaut photo (``--size`` pixels square, the
whole photo) under known head motion (rotation, scale, shift; engine.io.video.synth) for
each length, with a 16 kHz tone as its audio track, then imports each in a fresh process
(``engine.io.video.clips.read_video`` with the audio stored, what ``lipspace import`` runs):
the first import in the process is *cold* (mediapipe loaded, graph built), a second one
right after is *warm*. Prints per length: frames, min and median wall time of the
repeats, import fps, and the process's peak resident memory, which stays flat with the
video's length because frames are decoded and tracked one at a time (only ~1 KiB of
landmarks per frame is kept). Target: a 1-minute 30 fps video in under 2 minutes.

``--live`` also plays the shortest video as a live stream (paced at 30 fps, as a camera
delivers it) into a manifold built from its own import (app.models.live.LiveSession, the live
mirror's engine without the window) and prints the frames processed per second and the
frames dropped because tracking could not keep up. ``--live-window`` does the same
through the live mirror's window (drawing included; run under ``xvfb-run -a``).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RATE = 30


def make_video(path: Path, seconds: float, size: int) -> None:
    import numpy as np
    from skimage.data import astronaut
    from skimage.transform import resize

    from engine.io.video.synth import default_motion, moving_image_frames, write_video

    img = astronaut()
    if size != img.shape[0]:
        img = (resize(img, (size, size), anti_aliasing=True) * 255).round().astype(np.uint8)
    n = int(round(seconds * RATE))
    sr = 16000
    t = np.arange(int(seconds * sr)) / sr
    write_video(path, moving_image_frames(img, default_motion(n, rate=RATE)), RATE,
                audio=0.3 * np.sin(2 * np.pi * 220 * t), audio_rate=sr)


def child(path: str, audio_dir: str) -> dict:
    sys.path.insert(0, str(ROOT))
    from _common import blas_kernel, current_rss_mb, peak_rss_mb

    rss0 = current_rss_mb()
    t = time.perf_counter()
    from engine.io.video.clips import read_video

    c = read_video(path, audio_dir=audio_dir)
    cold = time.perf_counter() - t
    peak_cold = peak_rss_mb()
    t = time.perf_counter()
    c2 = read_video(path, audio_dir=audio_dir)
    warm = time.perf_counter() - t
    assert c2.n_frames == c.n_frames
    return {"frames": c.n_frames, "utterances": len(c.utterances), "cold_s": cold, "warm_s": warm,
            "peak_rss_cold_MiB": peak_cold, "rss_start_MiB": rss0,
            "peak_rss_MiB": peak_rss_mb(),
            "landmarks_MiB": c.frames.nbytes / 2**20, "blas": blas_kernel()}


def live(path: Path) -> None:
    from app.models.live import LiveSession
    from engine.io.video.clips import read_video
    from engine.manifold.model import Manifold

    m = Manifold(n_states=50).fit(read_video(path))
    s = LiveSession(m, str(path)).start()
    t0 = time.perf_counter()
    while True:
        _, st = s.poll()
        if st.finished or st.error:
            break
        time.sleep(0.05)
    wall = time.perf_counter() - t0
    s.stop()
    print(f"live stream of {path.name}: {st.received} frames received in {wall:.1f} s, {st.processed} processed, "
          f"{st.dropped} dropped ({100 * st.dropped / max(st.received, 1):.1f} %), "
          f"{st.processed / wall:.1f} frames/s processed; {st.error or 'no error'}")


def live_window(path: Path) -> None:
    """The same stream through the live mirror window (needs a display: run under xvfb-run)."""
    from PySide6 import QtCore, QtWidgets

    from app.models.live import LiveSession
    from app.views.live_view import LiveWindow
    from engine.io.video.clips import read_video
    from engine.manifold.model import Manifold

    m = Manifold(n_states=50).fit(read_video(path))
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    t0 = time.perf_counter()
    s = LiveSession(m, str(path)).start()
    w = LiveWindow(s)
    w.show()

    def check():
        if w.last_stats is not None and (w.last_stats.finished or w.last_stats.error):
            w.close()
            app.quit()

    timer = QtCore.QTimer()
    timer.timeout.connect(check)
    timer.start(100)
    app.exec()
    wall = time.perf_counter() - t0
    st = w.last_stats
    print(f"live mirror window on {path.name}: {st.received} frames received in {wall:.1f} s, {st.processed} "
          f"processed, {st.dropped} dropped ({100 * st.dropped / max(st.received, 1):.1f} %), "
          f"{w.renders.n_renders} renders ({w.renders.n_renders / wall:.1f} per s); {st.error or 'no error'}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, nargs="+", default=[20.0, 60.0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--size", type=int, default=512, help="video width = height in pixels (even)")
    ap.add_argument("--keep", default=None, help="folder for the generated videos (reused when present)")
    ap.add_argument("--live", action="store_true", help="also play the shortest video as a live stream")
    ap.add_argument("--live-window", action="store_true",
                    help="also play it through the live mirror window (needs a display, e.g. xvfb-run)")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    from _harness import Harness

    Harness.add_arguments(ap)
    a = ap.parse_args()
    if a.child:
        print(json.dumps(child(*a.child)))
        return
    sys.path.insert(0, str(ROOT))
    from _common import run_child_json

    bench = Harness("bench_video_import", a)

    folder = Path(a.keep) if a.keep else Path(tempfile.mkdtemp(prefix="bench-video-"))
    folder.mkdir(parents=True, exist_ok=True)
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f}, {os.cpu_count()} cores; "
          f"video {a.size}x{a.size} px at {RATE} fps, astronaut under head motion, 16 kHz audio")
    for sec in a.seconds:
        path = folder / f"astronaut_{a.size}_{sec:g}s.mp4"
        if not path.exists():
            t = time.perf_counter()
            make_video(path, sec, a.size)
            print(f"  made {path.name} in {time.perf_counter() - t:.1f} s ({path.stat().st_size / 2**20:.1f} MiB)")
        runs = []
        for _ in range(a.repeats):
            with tempfile.TemporaryDirectory() as aud:
                runs.append(run_child_json([sys.executable, __file__, "--child", path, aud]))
        n = runs[0]["frames"]
        cold = [r["cold_s"] for r in runs]
        warm = [r["warm_s"] for r in runs]
        peak = [r["peak_rss_cold_MiB"] for r in runs]
        print(f"{sec:5g} s video, {n} frames: cold (fresh process) min {min(cold):.1f} s median "
              f"{statistics.median(cold):.1f} s = {n / statistics.median(cold):.1f} fps; warm min {min(warm):.1f} s "
              f"median {statistics.median(warm):.1f} s = {n / statistics.median(warm):.1f} fps; peak RSS after the "
              f"first import median {statistics.median(peak):.0f} MiB (max {max(peak):.0f}), after both "
              f"{statistics.median(r['peak_rss_MiB'] for r in runs):.0f} MiB; landmarks kept "
              f"{runs[0]['landmarks_MiB']:.2f} MiB; {a.repeats} repeats")
        bench.figure(f"{sec:g}-s video ({n} frames), cold", cold, cold=True, peak_rss_mib=max(peak), headline=True,
                     show=False)
        bench.figure(f"{sec:g}-s video ({n} frames), warm", warm, cold=False, show=False,
                     peak_rss_mib=max(r["peak_rss_MiB"] for r in runs))
    print(f"BLAS: {runs[0]['blas']}")
    if a.live:
        live(folder / f"astronaut_{a.size}_{min(a.seconds):g}s.mp4")
    if a.live_window:
        live_window(folder / f"astronaut_{a.size}_{min(a.seconds):g}s.mp4")
    if not a.keep:
        import shutil

        shutil.rmtree(folder, ignore_errors=True)
    bench.finish()


if __name__ == "__main__":
    main()

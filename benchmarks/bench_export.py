"""Benchmark: a 3-second synthesised utterance exported as glTF (.glb) and rendered to MP4.

Usage: python benchmarks/bench_export.py [--preset default|paper|small] [--manifold FILE] [--seconds 3]
                                         [--repeat 5] [--cold 3] [--size 640x480] [--cache-dir DIR]

Goals (issue 17): the .glb of a 3-s utterance in under 1 s; the MP4 at least real time
(video seconds per wall-clock second >= 1) with software GL. Prints, per export, the
min and median wall time of ``--repeat`` warm runs in this process, the peak traced
memory (tracemalloc) of the first run and the max RSS, and ``--cold`` runs in fresh
processes (interpreter start, imports, loading the manifold file, synthesis and the
export; the export step's own time is reported separately). Also prints the BLAS
kernel (threadpoolctl) and the OpenGL renderer VTK uses.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


from _common import first_phones, peak_rss_mb, run_child_json  # noqa: E402
from _harness import Harness  # noqa: E402


def _synthesize(m, seconds):
    from engine.phonetics.targets import targets_from_phones
    from engine.synthesis.methods import make_synthesizer

    phones, _ = first_phones(m.corpus_, seconds)
    return make_synthesizer("viterbi", m, strict=False).synthesize(targets_from_phones(m, phones))


def _size(text):
    w, h = (int(v) for v in text.lower().split("x"))
    return w, h


def _child(kind, manifold_path, seconds, size, out):
    """One cold run in this fresh process; prints a JSON line of its timings."""
    t0 = time.perf_counter()
    from engine.manifold.model import Manifold

    m = Manifold.load(manifold_path)
    traj = _synthesize(m, seconds)
    t1 = time.perf_counter()
    if kind == "glb":
        from app.export.animation import export_animation

        export_animation(m, traj.Fx, out, rate=m.corpus_.rate)
    else:
        from app.export.video import render_video

        c = m.corpus_
        render_video(out, traj.frames(m), rate=c.rate, faces=c.faces, dims=c.dims, size=size)
    t2 = time.perf_counter()
    print(json.dumps({"load_and_synthesize": t1 - t0, "export": t2 - t1, "rss_mib": peak_rss_mb()}))


def _cold(kind, manifold_path, args, tmp, bench):
    walls, exports, rss = [], [], []
    for k in range(args.cold):
        out = Path(tmp) / f"cold{k}.{'glb' if kind == 'glb' else 'mp4'}"
        t = time.perf_counter()
        d = run_child_json([sys.executable, __file__, "--child", kind, "--manifold", manifold_path,
                            "--seconds", args.seconds, "--size", f"{args.size[0]}x{args.size[1]}", "--out", out])
        walls.append(time.perf_counter() - t)
        exports.append(d["export"])
        rss.append(d["rss_mib"])
    print(f"  cold {kind:<39} process min {min(walls):6.2f} s  median {np.median(walls):6.2f} s; "
          f"export step min {1000 * min(exports):8.1f} ms  median {1000 * np.median(exports):8.1f} ms "
          f"(of {args.cold}); max RSS {max(rss):6.0f} MiB", flush=True)
    bench.figure(f"cold {kind}: whole process", walls, cold=True, peak_rss_mib=max(rss))
    bench.figure(f"cold {kind}: export step", exports, cold=True, headline=kind == "glb")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--preset", default="default")
    ap.add_argument("--manifold", default=None, help="a saved manifold instead of fitting the preset")
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--cold", type=int, default=3)
    ap.add_argument("--size", type=_size, default=(640, 480))
    ap.add_argument("--cache-dir", default=None)
    ap.add_argument("--child", choices=("glb", "mp4"), default=None, help=argparse.SUPPRESS)
    ap.add_argument("--out", default=None, help=argparse.SUPPRESS)
    Harness.add_arguments(ap)
    args = ap.parse_args()
    if args.child:
        return _child(args.child, args.manifold, args.seconds, args.size, args.out)

    from engine.manifold.model import Manifold
    from engine.talker.synthetic import load_synthetic

    bench = Harness("bench_export", args)

    def timed(name, fn, *, repeat, per=None, headline=False):
        """The first call (its time includes first-use costs such as shader compilation), then
        ``repeat`` warm calls; ``per``: the video's length, printed as multiples of real time."""
        _, m = bench.measure(name, fn, repeat=repeat, cpu=True, headline=headline)
        if per:
            print(f"  {per / m.min:5.2f}x / {per / m.median:5.2f}x real time (min / median)", flush=True)
            bench.figure(f"{name}: x real time", [per / t for t in m.warm or m.values], "x", headline=headline)

    print(f"{os.cpu_count()} CPUs, python {sys.version.split()[0]}, numpy {np.__version__}")
    with tempfile.TemporaryDirectory(prefix="bench-export-") as tmp:
        if args.manifold:
            m = Manifold.load(args.manifold)
            mpath = Path(args.manifold)
        else:
            m = Manifold().fit(load_synthetic(preset=args.preset, cache_dir=args.cache_dir))
            mpath = m.save(Path(tmp) / "m.npz")
        c = m.corpus_
        traj = _synthesize(m, args.seconds)
        n = traj.n_frames
        dur = n / c.rate
        print(f"manifold: {c.n_frames} frames x {c.n_points} points ({0 if c.faces is None else len(c.faces)} "
              f"triangles), {m.shape_.n_components_} shape components, rate {c.rate:g} Hz")
        print(f"utterance: {n} frames = {dur:.2f} s")

        from app.export.animation import export_animation
        from app.export.video import render_video

        print("\nglTF (.glb) - goal < 1 s")
        glb = Path(tmp) / "speech.glb"
        timed("export_animation -> .glb (warm)", lambda: export_animation(m, traj.Fx, glb, rate=c.rate),
              repeat=args.repeat, headline=True)
        print(f"  file size {glb.stat().st_size / 2**20:.2f} MiB")
        _cold("glb", mpath, args, tmp, bench)

        print(f"\nMP4 (H.264, {args.size[0]}x{args.size[1]} per panel, {c.rate:g} fps) - goal >= real time")
        frames = traj.frames(m)
        mp4 = Path(tmp) / "talk.mp4"
        w = max(1, args.repeat - 2)
        timed("lips only (warm)", lambda: render_video(mp4, frames, rate=c.rate, faces=c.faces, dims=c.dims,
                                                       size=args.size), repeat=w, per=dur, headline=True)
        print(f"  file size {mp4.stat().st_size / 2**20:.2f} MiB")
        from engine.evaluation.measures import trajectory_y

        u = max(c.utterances, key=lambda x: x.n_frames)
        orig = c.frames[u.start:u.start + n]
        Y = trajectory_y(m, traj)
        timed("original beside + manifold panel (warm)",
              lambda: render_video(mp4, frames, rate=c.rate, faces=c.faces, dims=c.dims, original=orig, Y=Y,
                                   Y_original=m.Fy_[u.start:u.start + n], cloud=m.Fy_, size=args.size),
              repeat=w, per=dur)
        _cold("mp4", mpath, args, tmp, bench)
        import vtk

        rw = vtk.vtkRenderWindow()
        rw.SetOffScreenRendering(1)
        rw.Render()
        info = [ln for ln in rw.ReportCapabilities().splitlines() if "OpenGL renderer" in ln]
        print(f"\nVTK {vtk.vtkVersion.GetVTKVersion()}, {type(rw).__name__}: {info[0].strip() if info else '?'}; "
              f"DISPLAY={os.environ.get('DISPLAY', '(none)')}")
        rw.Finalize()
        bench.fact(gl_renderer=info[0].strip() if info else "?")
    bench.finish()


if __name__ == "__main__":
    main()

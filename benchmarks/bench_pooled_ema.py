"""The issue-13 articulograph case: a pooled 3-D EMA corpus of 276,927 frames (12 coordinates, 250 Hz), K = 3,000.

The corpus: the two Haskins IEEE sample recordings (``/work/shared/data/haskins-ieee``
beside the project, 100 Hz MVIEW; sensors UL, LL, ML (mouth corner), JAW in 3-D = 12
coordinates) resampled to 250 Hz with the importer's anti-aliasing resampler, then
pooled by repetition with jitter until it holds 276,927 frames: every copy of a
recording is time-stretched by a factor drawn from [0.85, 1.15] (linear interpolation),
its deviations from the recording's mean scaled by a gain from [0.9, 1.1], and
Gaussian noise of 0.05 mm added to every coordinate. Each copy is one utterance (no
phones). A copy is *not* new speech: the pool has the size and shape of the issue's
corpus, not its variety.

The build is ``Manifold()`` with the defaults (the size rule: landmark embedding with
2,000 landmarks, mini-batch K-means, K = 3,000 states), run once per repeat, each in a
fresh process (cold: libraries imported, corpus made, then the build timed). Printed:
wall time per stage, the build's peak resident memory (sampled every 10 ms), the BLAS
kernel and the load average before and after. ``--dask local`` runs the heavy stages
on a LocalCluster (workers' peak RSS printed too).

Usage::

    python benchmarks/bench_pooled_ema.py [--repeats 1] [--dask local]
"""
from __future__ import annotations

import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import blas_kernel, run_child_json  # noqa: E402
from _harness import Harness  # noqa: E402

N_FRAMES = 276_927
RATE = 250.0
SENSORS = ["UL", "LL", "ML", "JAW"]
DATA = os.path.join(os.path.dirname(ROOT), "shared", "data", "haskins-ieee")


def pooled_corpus(n_frames: int = N_FRAMES, seed: int = 0):
    """The pooled corpus described above (engine.recordings.corpus.Corpus, n_frames frames)."""
    from dataclasses import replace

    import numpy as np

    from engine.io import read_corpus, resample
    from engine.recordings.corpus import Corpus

    files = sorted(os.path.join(DATA, f) for f in os.listdir(DATA) if f.endswith(".mat"))
    if not files:
        raise SystemExit(f"no Haskins .mat files in {DATA}")
    recs = [resample(read_corpus(f, sensors=SENSORS), RATE) for f in files]
    rng = np.random.default_rng(seed)
    chunks, utts, n, i = [], [], 0, 0
    while n < n_frames:
        rec = recs[i % len(recs)]
        F = rec.frames.astype(np.float64)
        m = len(F)
        k = max(8, int(round(m * rng.uniform(0.85, 1.15))))
        src = np.linspace(0, m - 1, k)
        Fk = np.stack([np.interp(src, np.arange(m), F[:, j]) for j in range(F.shape[1])], axis=1)
        mu = F.mean(axis=0)
        Fk = mu + rng.uniform(0.9, 1.1) * (Fk - mu) + rng.normal(0, 0.05, Fk.shape)
        k = min(k, n_frames - n)
        if k < 8:  # too short to be an utterance: lengthen the previous one's end instead
            break
        chunks.append(Fk[:k])
        u = rec.utterances[0]
        utts.append(replace(u, id=f"{u.id}_copy{i:04d}", start=n, stop=n + k, phones=[]))
        n += k
        i += 1
    frames = np.concatenate(chunks).astype(np.float32)
    base = recs[0]
    return Corpus(frames=frames, rate=RATE, utterances=utts, dims=3, point_names=list(base.point_names),
                  name="haskins-pooled", point_roles=base.point_roles, registration=base.registration,
                  history=list(base.history) + [f"pooled by repetition with jitter to {len(frames)} frames"])


def one(dask: str | None) -> dict:
    from bench_scale import measured_build

    load0 = os.getloadavg()
    corpus = pooled_corpus()
    b = measured_build(corpus, dask)
    m, wall, cpu, start, peak, workers = b["manifold"], b["wall"], b["cpu"], b["start"], b["peak"], b["workers"]
    return {"n_frames": corpus.n_frames, "coords": corpus.frames.shape[1], "utterances": len(corpus.utterances),
            "K": int(m.states_.centroids_.shape[0]), "L": m.embedding_.reference_.shape[0],
            "wall_s": wall, "client_cpu_s": cpu, "stages": m.timings_, "rss_start_mb": start, "rss_peak_mb": peak,
            "worker_peak_mb": workers, "blas": blas_kernel(), "load_before": load0, "load_after": os.getloadavg()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--dask", default=None, help="'local' or a scheduler address (default: in-process)")
    ap.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    Harness.add_arguments(ap)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(one(args.dask)))
        return 0
    bench = Harness("bench_pooled_ema", args)
    walls, peaks = [], []
    for r in range(args.repeats):
        cmd = [sys.executable, os.path.abspath(__file__), "--one"] + (["--dask", args.dask] if args.dask else [])
        res = run_child_json(cmd)
        walls.append(res["wall_s"])
        peaks.append(res["rss_peak_mb"])
        st = ", ".join(f"{k} {v:.1f}" for k, v in res["stages"].items())
        worker_peaks = ", ".join(f"{w:.0f}" for w in res["worker_peak_mb"])
        wk = f"; workers' peak {worker_peaks} MB" if res["worker_peak_mb"] else ""
        print(f"repeat {r}: {res['n_frames']} frames x {res['coords']} coordinates, {res['utterances']} utterances, "
              f"L = {res['L']}, K = {res['K']}: build {res['wall_s']:.1f} s wall, "
              f"client CPU {res['client_cpu_s']:.1f} s "
              f"({st}); RSS at start {res['rss_start_mb']:.0f} MB, peak {res['rss_peak_mb']:.0f} MB{wk}; "
              f"load average {res['load_before'][0]:.1f} before, {res['load_after'][0]:.1f} after "
              f"({os.cpu_count()} cores)", flush=True)
    import statistics

    print(f"build wall over {len(walls)} cold run(s): min {min(walls):.1f} s, median {statistics.median(walls):.1f} s; "
          f"dask: {args.dask or 'no (in-process)'}\nBLAS: {res['blas']}")
    bench.figure("build wall", walls, cold=True, peak_rss_mib=max(peaks), headline=True, show=False,
                 dask=args.dask or "in-process", frames=res["n_frames"], stages=res["stages"])
    bench.finish()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

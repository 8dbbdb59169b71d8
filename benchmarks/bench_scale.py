"""Wall time and peak memory of the whole build at growing N (issue 13).

For each N the synthetic talker speaks N frames (60 Hz) and ``Manifold().fit`` builds
its manifold, each size in a fresh process (cold). The build follows the size rule of
``engine.buildplan``: the exact embedding up to 50,000 frames, 2,000 landmarks above.
Printed per size: the path taken, wall time per stage (shape, dynamics, embedding,
tangent, states), the process's resident memory when the build starts (corpus loaded,
libraries imported), the build's peak resident memory (sampled every 10 ms during the
build only, so the corpus generator's own peak does not count), their difference, and
at the end the fitted exponent b of ``build memory ~ N^b`` and ``time ~ N^b`` over the
sizes. Memory linear in N means b <= 1.

Points per frame: ``--resolution small`` (156 points, 468 coordinates) by default for
every size so that the sizes are comparable; ``--resolution paper`` gives the paper's
4,260 points (12,780 coordinates; 1.5 GB of frames at 30k).

``--dask local`` runs the shape space and the embedding on a LocalCluster (one worker
per core); the workers' peak resident memory is then printed beside the client's.

Usage::

    python benchmarks/bench_scale.py                          # 30k, 100k, 300k
    python benchmarks/bench_scale.py --sizes 30000 100000 300000 1000000
    python benchmarks/bench_scale.py --sizes 30000 --resolution paper
    python benchmarks/bench_scale.py --sizes 100000 --dask local
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import blas_kernel, current_rss_mb  # noqa: E402


class _PeakSampler(threading.Thread):
    """Highest VmRSS seen while running (sampled every ``interval`` s)."""

    def __init__(self, interval=0.01):
        super().__init__(daemon=True)
        self.interval, self.peak, self._halt = interval, current_rss_mb(), threading.Event()

    def run(self):
        while not self._halt.is_set():
            self.peak = max(self.peak, current_rss_mb())
            time.sleep(self.interval)

    def stop(self) -> float:
        self._halt.set()
        self.join()
        self.peak = max(self.peak, current_rss_mb())
        return self.peak


def _worker_peak_mb():
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def measured_build(corpus, dask: str | None) -> dict:
    """``Manifold().fit(corpus)`` (on Dask when ``dask`` names a cluster), measured: the manifold,
    wall and client CPU seconds, resident memory at the start and peak (MB), the workers' peaks."""
    import warnings

    from engine.manifold import Manifold

    executor = None
    if dask:
        from engine.scale import DaskExecutor

        executor = DaskExecutor.connect(dask)
    start = current_rss_mb()
    sampler = _PeakSampler()
    sampler.start()
    c0, t = time.process_time(), time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # connectivity warnings of the state graph are not the point here
        m = Manifold().fit(corpus, executor=executor)
    wall, cpu = time.perf_counter() - t, time.process_time() - c0
    peak = sampler.stop()
    workers = None
    if executor is not None:
        workers = sorted(executor.client.run(_worker_peak_mb).values())
        executor.close()
    return {"manifold": m, "wall": wall, "cpu": cpu, "start": start, "peak": peak, "workers": workers}


def one(n_frames: int, resolution: str, dask: str | None) -> dict:
    """Generate N frames, build, and measure (run in a fresh process)."""
    from engine.buildplan import plan_build
    from engine.synthetic import SyntheticTalker

    t = time.perf_counter()
    corpus = SyntheticTalker(duration=n_frames / 60.0, resolution=resolution).generate()
    t_gen = time.perf_counter() - t
    b = measured_build(corpus, dask)
    m, wall, start, peak, workers = b["manifold"], b["wall"], b["start"], b["peak"], b["workers"]
    return {"n_frames": corpus.n_frames, "coords": corpus.frames.shape[1], "generate_s": t_gen,
            "plan": plan_build(corpus.n_frames).describe(), "wall_s": wall, "stages": m.timings_,
            "rss_start_mb": start, "rss_peak_mb": peak, "build_mb": peak - start,
            "worker_peak_mb": workers, "frames_mb": corpus.frames.nbytes / 2**20, "blas": blas_kernel(),
            "dask": dask}


def _exponent(ns, ys):
    import numpy as np

    ns, ys = np.log(np.asarray(ns, float)), np.log(np.maximum(np.asarray(ys, float), 1e-9))
    return float(np.polyfit(ns, ys, 1)[0]) if len(ns) > 1 else float("nan")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[30000, 100000, 300000])
    ap.add_argument("--resolution", default="small", help="lip model resolution (small: 156 points, paper: 4,260)")
    ap.add_argument("--dask", default=None, help="'local' or a scheduler address (default: in-process)")
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(one(args.one, args.resolution, args.dask)))
        return 0
    runs = []
    for n in args.sizes:
        cmd = [sys.executable, os.path.abspath(__file__), "--one", str(n), "--resolution", args.resolution]
        if args.dask:
            cmd += ["--dask", args.dask]
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            print(f"N={n}: failed\n{out.stderr[-2000:]}", file=sys.stderr)
            return 1
        r = json.loads(out.stdout.strip().splitlines()[-1])
        runs.append(r)
        st = ", ".join(f"{k} {v:.1f}" for k, v in r["stages"].items())
        wk = f"; workers' peak {', '.join(f'{w:.0f}' for w in r['worker_peak_mb'])} MB" if r["worker_peak_mb"] else ""
        print(f"{r['plan']}\n  {r['coords']} coordinates ({r['frames_mb']:.0f} MB of frames), generated in "
              f"{r['generate_s']:.1f} s; build {r['wall_s']:.1f} s wall ({st}); RSS at start "
              f"{r['rss_start_mb']:.0f} MB, peak {r['rss_peak_mb']:.0f} MB, build +{r['build_mb']:.0f} MB{wk}",
              flush=True)
    if runs:
        print(f"BLAS: {runs[0]['blas']}; dask: {args.dask or 'no (in-process)'}")
    if len(runs) > 1:
        ns = [r["n_frames"] for r in runs]
        print(f"fitted exponents over N = {ns}: build memory ~ N^{_exponent(ns, [r['build_mb'] for r in runs]):.2f}, "
              f"peak RSS ~ N^{_exponent(ns, [r['rss_peak_mb'] for r in runs]):.2f}, "
              f"wall ~ N^{_exponent(ns, [r['wall_s'] for r in runs]):.2f}")
        for k in runs[0]["stages"]:
            print(f"  {k}: wall ~ N^{_exponent(ns, [r['stages'][k] for r in runs]):.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

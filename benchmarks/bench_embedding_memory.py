"""Peak memory of the embedding (PCA of the N x N distance matrix) at growing N.

The embedding promises O(N·k + block·N) memory: D is never formed, each block of its
rows is made, used and dropped. Until issue 16 the first pass kept one length-N
column-sum vector per block, and with blocks of 96 MiB / (4N) rows that grew as N^3
(230k frames took 9.3 GB). This script fits ``engine.manifold.embedding.Embedding`` on dynamic
features of a small point set at N = 50k, 100k, 200k (by default) frames, each fit in
a fresh process, and prints wall time, the process's peak resident memory, the memory
held when the fit starts (the input G and the libraries), their difference (an upper
bound of the fit's working memory), and its growth from one size to the next (at most
the ratio of the sizes = linear; the old code grew as N^3).

The features G are those of a smooth random trajectory of ``--points`` points through
the real pipeline's shape space and dynamic features (m shape components, 2m
columns), so the embedding sees data shaped like a corpus's. Memory does not depend
on the number of power iterations, so ``--n-iter`` (default 0: two passes over D)
only shortens the run; pass 2 for the build's own setting.

Usage::

    python benchmarks/bench_embedding_memory.py               # 50k, 100k, 200k
    python benchmarks/bench_embedding_memory.py --sizes 20000 40000 --repeat 3
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import current_rss_mb, peak_rss_mb, run_child_json  # noqa: E402
from _harness import Harness  # noqa: E402


def features(n_frames: int, n_points: int, seed: int = 0):
    """Dynamic features G (N, 2m) of a smooth random trajectory of ``n_points`` 3-D points."""
    import numpy as np

    from engine.manifold.dynamics import DynamicFeatures
    from engine.manifold.shape import ShapeSpace
    from engine.recordings.bounds import velocities

    rng = np.random.default_rng(seed)
    n_ctrl = 6  # a few articulatory controls drive the points, like the synthetic talker
    t = np.arange(n_frames) / 60.0
    freqs = rng.uniform(0.5, 4.0, size=n_ctrl)
    phases = rng.uniform(0, 2 * np.pi, size=n_ctrl)
    ctrl = np.sin(2 * np.pi * freqs[None, :] * t[:, None] + phases) + 0.05 * rng.standard_normal((n_frames, n_ctrl))
    basis = rng.standard_normal((n_ctrl, 3 * n_points))
    F = (ctrl @ basis + 0.01 * rng.standard_normal((n_frames, 3 * n_points))).astype(np.float32)
    bounds = np.array([[0, n_frames]])
    shape = ShapeSpace(max_components=10, variance=0.99).fit(F)
    Fx = shape.transform(F)
    Fxv = velocities(Fx, bounds)
    return DynamicFeatures().fit(Fx, bounds).transform_pair(Fx, Fxv)


def one(n_frames: int, n_points: int, n_iter: int) -> dict:
    """Fit once in this process; return the measurements."""
    import numpy as np

    from engine.manifold.embedding import Embedding

    G = np.ascontiguousarray(features(n_frames, n_points), dtype=np.float32)
    before = peak_rss_mb()
    held = current_rss_mb()
    t = time.perf_counter()
    emb = Embedding(n_components=10, n_iter=n_iter).fit(G)
    wall = time.perf_counter() - t
    peak = peak_rss_mb()
    return {"N": n_frames, "cols": int(G.shape[1]), "wall_s": wall, "peak_mb": peak, "held_mb": held,
            "peak_before_fit_mb": before, "passes": emb.n_passes_}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[50_000, 100_000, 200_000], help="frame counts N")
    ap.add_argument("--points", type=int, default=20, help="points per frame (default: %(default)s)")
    ap.add_argument("--n-iter", type=int, default=0, help="power iterations (default: %(default)s)")
    ap.add_argument("--repeat", type=int, default=1, help="fresh-process fits per size (default: %(default)s)")
    ap.add_argument("--one", type=int, default=None, help=argparse.SUPPRESS)
    Harness.add_arguments(ap)
    args = ap.parse_args(argv)
    if args.one is not None:
        print(json.dumps(one(args.one, args.points, args.n_iter)))
        return 0
    import numpy as np

    bench = Harness("bench_embedding_memory", args)
    print(f"embedding memory: PCA of D, k=10, n_iter={args.n_iter}, {args.points} points per frame; "
          f"{os.cpu_count()} CPUs; numpy {np.__version__}")
    print(f"{'N':>8} {'2m':>3} {'passes':>6} {'wall min/med s':>15} {'peak MB':>9} {'input MB':>9} "
          f"{'peak-input MB':>13} {'growth':>7}")
    prev = None
    for n in args.sizes:
        runs = []
        for _ in range(args.repeat):  # each run in a fresh process: the peak is per process
            runs.append(run_child_json([sys.executable, os.path.abspath(__file__), "--one", str(n), "--points",
                                        str(args.points), "--n-iter", str(args.n_iter)]))
        walls = [r["wall_s"] for r in runs]
        peak = max(r["peak_mb"] for r in runs)
        held = max(r["held_mb"] for r in runs)
        added = max(r["peak_mb"] - r["held_mb"] for r in runs)  # the fit's working memory (upper bound)
        growth = f"{added / prev:.2f}x" if prev else "-"
        prev = added
        print(f"{n:>8} {runs[0]['cols']:>3} {runs[0]['passes']:>6} {min(walls):>7.1f}/{statistics.median(walls):<7.1f} "
              f"{peak:>9.0f} {held:>9.0f} {added:>13.0f} {growth:>7}")
        bench.figure(f"N={n}: fit wall", walls, cold=True, peak_rss_mib=peak, headline=True, held_mib=held,
                     added_mib=added, passes=runs[0]["passes"], show=False)
    bench.finish()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Benchmark: state graph and tangent frames at paper scale; hemisphere and path query times.

Usage: python benchmarks/bench_states.py [--source synthetic|standin] [--preset paper] [--repeats 21]
       python benchmarks/bench_states.py --source standin --frames 600000 --states 20000   # issue 13 item 8

Data: the paper-scale synthetic talker (``engine.synthetic``, preset "paper") put through
the manifold pipeline (shape space, dynamic features, embedding) when ``--source
synthetic`` (the default, if ``engine.synthetic`` is importable). ``--source standin``
(or no ``engine.synthetic``) uses a stand-in with the paper's N = 28,833 frames: speech-like
opening trajectories (critically damped articulator driven by random phone targets, 60 Hz,
utterances of 1.5-3.5 s) embedded as a paraboloid-shaped sheet in 3-D, F^y = (x, v, x^2 - v^2/2)
plus noise, with F^x = (x, ...) and F^x' its first differences; ``--frames N`` sets its size
(600,000 frames give K = 20,000 states their default 30 frames each). The output says which.

Measured: fit of TangentFrames and of StateGraph at K = 1,000 and 5,000; then for each K the
median wall time (over ``--repeats``) of

* the future + past hemispheres of one state (two Dijkstra runs), and
* a 10-state minimum-distance path (10 states in sequence, 9 legs, ``min_path`` per leg),

with peak traced memory (tracemalloc) and the process's max RSS. Target: each query well
under 20 ms.
"""
from __future__ import annotations

import argparse
import os
import resource
import time
import tracemalloc
import warnings

import numpy as np

PAPER_FRAMES = 28833


def _rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _timed(fn):
    tracemalloc.start()
    tracemalloc.reset_peak()
    c, t = time.process_time(), time.perf_counter()
    out = fn()
    dt, cpu = time.perf_counter() - t, time.process_time() - c
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    return out, dt, peak, f"CPU {cpu:6.2f} s (load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)"


def standin(n_frames=PAPER_FRAMES, seed=0, rate=60.0):
    """Paper-sized stand-in: (Fy (N, 3), Fx (N, 2), Fxv (N, 2), bounds (U, 2), true aperture (N,))."""
    rng = np.random.default_rng(seed)
    lengths = []
    while sum(lengths) < n_frames:
        lengths.append(int(rng.integers(90, 210)))
    lengths[-1] -= sum(lengths) - n_frames
    if lengths[-1] < 2:
        lengths[-2] += lengths.pop()
    w = 2 * np.pi * 6.0 / rate
    x = np.empty(n_frames)
    i = 0
    for n in lengths:
        target = np.zeros(n)
        j = 6
        while j < n - 6:
            L = int(rng.integers(4, 13))
            target[j:j + L] = rng.uniform(0, 1) ** 0.7
            j += L
        xi = vi = 0.0
        for t in range(n):  # critically damped second-order articulator
            vi += w * w * (target[t] - xi) - 2 * w * vi
            xi += vi
            x[i + t] = xi
        i += n
    bounds = np.column_stack([np.cumsum([0] + lengths[:-1]), np.cumsum(lengths)])
    v = np.zeros_like(x)
    v[1:] = x[1:] - x[:-1]
    v[bounds[:, 0]] = v[np.minimum(bounds[:, 0] + 1, bounds[:, 1] - 1)]
    xs = (x - x.mean()) / np.abs(x - x.mean()).max()
    vs = (v - v.mean()) / np.abs(v - v.mean()).max()
    Fy = np.column_stack([xs, vs, xs**2 - 0.5 * vs**2]) + 0.01 * rng.standard_normal((n_frames, 3))
    Fx = np.column_stack([x, 0.1 * rng.standard_normal(n_frames)])
    Fxv = np.column_stack([v, np.zeros(n_frames)])
    return Fy.astype(np.float32), Fx.astype(np.float32), Fxv.astype(np.float32), bounds, x


def synthetic(preset):
    from engine.dynamics import DynamicFeatures, velocities
    from engine.embedding import Embedding
    from engine.shape import ShapeSpace
    from engine.synthetic import load_synthetic

    corpus = load_synthetic(preset=preset)
    b = corpus.bounds
    Fx = ShapeSpace().fit(corpus.frames).transform(corpus.frames)
    Fxv = velocities(Fx, b)
    G = DynamicFeatures().fit(Fx, b).transform_pair(Fx, Fxv)
    Fy = Embedding(n_components=10).fit(G).embedding_
    return Fy, Fx, Fxv, b, corpus


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", choices=("synthetic", "standin"), default=None)
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--repeats", type=int, default=21)
    ap.add_argument("--states", type=int, nargs="+", default=[1000, 5000])
    ap.add_argument("--frames", type=int, default=PAPER_FRAMES, help="frames of the stand-in (default: the paper's)")
    args = ap.parse_args()

    from engine.states import StateGraph, StateGraphConnectivityWarning, UnreachableError
    from engine.tangent import TangentFrames

    source = args.source
    if source is None:
        try:
            import engine.synthetic  # noqa: F401
            source = "synthetic"
        except ImportError:
            source = "standin"
    t = time.perf_counter()
    if source == "synthetic":
        Fy, Fx, Fxv, b, corpus = synthetic(args.preset)
        print(f"data: engine.synthetic preset {args.preset!r} through shape/dynamics/embedding: "
              f"{len(Fy)} frames x {corpus.frames.shape[1]} coordinates, {len(b)} utterances "
              f"({time.perf_counter() - t:.1f} s to build)")
    else:
        Fy, Fx, Fxv, b, _ = standin(args.frames)
        print(f"data: STAND-IN (paraboloid sheet of speech-like opening trajectories), {len(Fy)} frames, "
              f"{len(b)} utterances (engine.synthetic not used)")

    tan, dt, peak, cpu = _timed(lambda: TangentFrames().fit(Fy, Fx, Fxv, b))
    print(f"TangentFrames.fit (k=20)        {dt * 1e3:9.1f} ms   {cpu}   peak traced {peak:7.1f} MiB   "
          f"max RSS {_rss_mb():7.1f} MiB")
    print("  classes " + ", ".join(f"{k} {100 * v:.1f}%" for k, v in tan.class_proportions().items()))

    rng = np.random.default_rng(1)
    for K in args.states:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", StateGraphConnectivityWarning)
            g, dt, peak, cpu = _timed(lambda: StateGraph(n_states=K).fit(Fy, b))
        print(f"\nStateGraph.fit K={K:<6}         {dt * 1e3:9.1f} ms   {cpu}   peak traced {peak:7.1f} MiB   "
              f"max RSS {_rss_mb():7.1f} MiB")
        print("  " + g.connectivity_report().replace("\n", "\n  "))
        for w in caught:
            print(f"  warning: {w.message}")
        big = np.flatnonzero(g.scc_labels_ == g.largest_scc_)
        seeds = rng.choice(big, size=args.repeats)
        g.hemispheres(int(seeds[0]))  # build the cached csr forms once
        times = []
        for s in seeds:
            t = time.perf_counter()
            g.hemispheres(int(s))
            times.append(time.perf_counter() - t)
        print(f"  future+past hemispheres, one state: median {np.median(times) * 1e3:7.2f} ms "
              f"(min {np.min(times) * 1e3:.2f}, max {np.max(times) * 1e3:.2f}, {args.repeats} states)")
        times, hops = [], []
        for _ in range(args.repeats):
            way = rng.choice(big, size=10, replace=False)
            t = time.perf_counter()
            try:
                legs = [g.min_path(int(a), int(c)) for a, c in zip(way[:-1], way[1:])]
            except UnreachableError:  # cannot happen inside one strongly connected component
                raise
            path = np.concatenate([legs[0]] + [leg[1:] for leg in legs[1:]])
            times.append(time.perf_counter() - t)
            hops.append(len(path) - 1)
        print(f"  10-state min-distance path (9 legs): median {np.median(times) * 1e3:7.2f} ms "
              f"(min {np.min(times) * 1e3:.2f}, max {np.max(times) * 1e3:.2f}); "
              f"median length {int(np.median(hops))} hops")
        tracemalloc.start()
        g.hemispheres(int(seeds[0]))
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
        print(f"  peak traced memory of one hemisphere query {peak:.2f} MiB; max RSS {_rss_mb():.1f} MiB")


if __name__ == "__main__":
    main()

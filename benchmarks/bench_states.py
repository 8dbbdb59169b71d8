"""Benchmark: state graph and tangent frames at paper scale; hemisphere and path query times.

Usage: python benchmarks/bench_states.py [--source synthetic|standin] [--preset paper] [--repeats 21]
       python benchmarks/bench_states.py --source standin --frames 600000 --states 5000 20000 \
           --no-tangent --reuse /tmp/graphs   # issue 13 item 8: queries at K = 5,000 and 20,000

Data: the paper-scale synthetic talker (``engine.talker.synthetic``, preset "paper") put through
the manifold pipeline (shape space, dynamic features, embedding) when ``--source
synthetic`` (the default, if ``engine.talker.synthetic`` is importable). ``--source standin``
(or no ``engine.talker.synthetic``) uses a stand-in with the paper's N = 28,833 frames: speech-like
opening trajectories (critically damped articulator driven by random phone targets, 60 Hz,
utterances of 1.5-3.5 s) embedded as a paraboloid-shaped sheet in 3-D, F^y = (x, v, x^2 - v^2/2)
plus noise, with F^x = (x, ...) and F^x' its first differences; ``--frames N`` sets its size
(600,000 frames give K = 20,000 states their default 30 frames each). The output says which.

Measured: fit of TangentFrames and of StateGraph at each ``--states`` K (``--reuse DIR``
keeps the fitted graphs in DIR and loads them on later runs: fitting K = 20,000 takes
minutes and does not change the queries); then for each K

* the future + past hemispheres of one state (``StateGraph.hemispheres``: what the
  explorer colours on a click), and
* a 10-state minimum-distance path: 10 states of the largest strongly connected
  component in sequence, 9 legs, ``StateGraph.min_path`` per leg (the explorer's state
  path runs one leg per change of selection or target), beside the same paths by one
  whole breadth-first search per leg (``min_path`` before the bidirectional search),

each **warm** (the same process, after one query has built the cached csr forms: min and
median of ``--repeats`` queries, wall and CPU time) and **cold** (``--cold-runs`` fresh
processes, each loading the saved graph and timing its first query: right after loading,
so building A and A^T as csr is included, and after ``StateGraph.prepare_queries``, which
the explorer's loading worker calls; loading is timed apart). Also the state path
``lipspace synthesize`` and ``StateModel.path`` find: 10 targets (the states of every 6th
frame of a training utterance, 0.1 s apart at 60 Hz), each gap the most probable path of
exactly its length (``engine.graph.bridges.bridge``),
beside the full recursion over every edge it replaced (``MaxProductGraph.viterbi`` +
``backtrack``) on the same targets, min / median of ``--synthesis-repeats``; and the
phone lattice of ``synthesize --text`` (scores from up to 8 candidate states per target
to the next target's, ``engine.graph.bridges.forward_to`` beside ``MaxProductGraph.forward``).
Every line carries the load average; the BLAS kernel is printed once (no query calls BLAS).
Target (issue 13 item 8): hemisphere and path <= 20 ms at K = 20,000.
"""
from __future__ import annotations

import argparse
import os
import time
import tracemalloc
import warnings

import numpy as np
from _common import peak_rss_mb, run_child_json
from _harness import Harness

PAPER_FRAMES = 28833


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
    from engine.manifold.dynamics import DynamicFeatures
    from engine.manifold.embedding import Embedding
    from engine.manifold.shape import ShapeSpace
    from engine.recordings.bounds import velocities
    from engine.talker.synthetic import load_synthetic

    corpus = load_synthetic(preset=preset)
    b = corpus.bounds
    Fx = ShapeSpace().fit(corpus.frames).transform(corpus.frames)
    Fxv = velocities(Fx, b)
    G = DynamicFeatures().fit(Fx, b).transform_pair(Fx, Fxv)
    Fy = Embedding(n_components=10).fit(G).embedding_
    return Fy, Fx, Fxv, b, corpus


def _child(path, query, seed, prepared):
    """Fresh process: load the saved graph (and ``prepare_queries`` if ``prepared``), time
    the first ``query``; prints one JSON line."""
    import json

    t = time.perf_counter()
    from engine.files.persist import load_estimator, read_npz
    from engine.graph.states import StateGraph

    g = load_estimator(StateGraph, read_npz(path), "states")
    if prepared:
        g.prepare_queries()
    t_load = time.perf_counter() - t
    big = np.flatnonzero(g.scc_labels_ == g.largest_scc_)
    rng = np.random.default_rng(seed)
    t = time.perf_counter()
    if query == "hemisphere":
        g.hemispheres(int(rng.choice(big)))
    else:
        _ten_state_path(g, rng.choice(big, size=10, replace=False))
    print(json.dumps({"load_s": t_load, "query_s": time.perf_counter() - t}))


def _ten_state_path(g, way):
    legs = [g.min_path(int(a), int(c)) for a, c in zip(way[:-1], way[1:])]
    return np.concatenate([legs[0]] + [leg[1:] for leg in legs[1:]])


def _ten_state_path_before(g, way):
    """The same path as ``min_path`` gave before the bidirectional search: one whole
    breadth-first search per leg, the path read off its predecessor tree."""
    from scipy.sparse.csgraph import breadth_first_order

    G, out = g._graph(False), [int(way[0])]
    for a, c in zip(way[:-1], way[1:]):
        pred = breadth_first_order(G, int(a), directed=True, return_predecessors=True)[1]
        leg = [int(c)]
        while leg[-1] != a:
            leg.append(int(pred[leg[-1]]))
        out += leg[::-1][1:]
    return np.array(out)


def _load_avg():
    return f"load average {os.getloadavg()[0]:.1f}"


def _stats(times, cpu=None):
    t = np.asarray(times) * 1e3
    out = f"min {t.min():7.2f} ms, median {np.median(t):7.2f} ms, max {t.max():7.2f} ms over {t.size}"
    if cpu is not None:  # the process's CPU time: what the query costs, without the wait for a core
        c = np.asarray(cpu) * 1e3
        out += f" (CPU min {c.min():.2f} ms, median {np.median(c):.2f} ms)"
    return out


def _cold(path, query, runs, bench, K):
    """First query in fresh processes: right after loading, and after ``prepare_queries``
    (what the explorer's loading worker does), alternating; both kept as cold figures."""
    import sys

    load, first = {0: [], 1: []}, {0: [], 1: []}
    for seed in range(runs):
        for prepared in (0, 1):
            r = run_child_json([sys.executable, __file__, "--child", path, query, seed, prepared])
            load[prepared].append(r["load_s"]), first[prepared].append(r["query_s"])
    bench.figure(f"K={K} {query}: first query after loading", first[0], cold=True)
    bench.figure(f"K={K} {query}: first query after prepare_queries", first[1], cold=True,
                 load_s_median=float(np.median(load[1])))
    return (f"first query right after loading {_stats(first[0])} fresh processes; after prepare_queries() "
            f"(the explorer's loader) {_stats(first[1])} (import + load of the graph: median "
            f"{np.median(load[0]):.2f} s, with prepare_queries {np.median(load[1]):.2f} s, not included); "
            f"{_load_avg()}")


def _max_product_graph(g):
    """The state graph ``g``'s observed transitions as the ``MaxProductGraph`` synthesis runs
    on, and the seconds it took to set up."""
    from engine.synthesis.viterbi import MaxProductGraph, log_transitions, observed_transitions

    t = time.perf_counter()
    mg = MaxProductGraph(log_transitions(observed_transitions(g)))
    return mg, time.perf_counter() - t


def _synthesis_path(mg, g, bounds, rng, repeats, gap=6, n_targets=10):
    """Per repeat: the 9 gaps' state paths on ``mg`` (:func:`_max_product_graph` of ``g``) by
    ``engine.graph.bridges.bridge`` (what ``lipspace synthesize`` and ``StateModel.path`` run) and by
    the full recursion over every edge (``viterbi`` + ``backtrack``, before), same targets,
    alternating; the paths must agree."""
    from engine.graph.bridges import bridge

    span = gap * (n_targets - 1)
    long = bounds[(bounds[:, 1] - bounds[:, 0]) > span]
    now, full = [], []
    for r in range(repeats + 1):  # the first (builds the out-edge index once) is not kept
        u = long[rng.integers(len(long))]
        f0 = int(rng.integers(u[0], u[1] - span))
        targets = [int(s) for s in g.labels_[f0: f0 + span + 1: gap]]
        t = time.perf_counter()
        paths = [bridge(mg, a, b, gap + 1) for a, b in zip(targets[:-1], targets[1:])]
        t_now = time.perf_counter() - t
        t = time.perf_counter()
        ref = []
        for a, b in zip(targets[:-1], targets[1:]):
            scores, hist = mg.viterbi(a, gap + 1)
            ref.append(mg.backtrack(hist, b))
        t_full = time.perf_counter() - t
        assert all(np.array_equal(p, q) for p, q in zip(paths, ref)), "bridge differs from the full recursion"
        if r:
            now.append(t_now), full.append(t_full)
    return now, full


def _lattice_scores(mg, g, bounds, rng, repeats, gap=6, n_targets=10, n_candidates=8):
    """The phone lattice of ``synthesize --text``: for each gap, the best ``gap + 1``-frame
    path scores from every candidate state of one target to every candidate of the next
    (candidates: the distinct states of the 8 frames around each target frame), by
    ``engine.graph.bridges.forward_to`` and by the full ``MaxProductGraph.forward`` on ``mg``
    (:func:`_max_product_graph` of ``g``), alternating."""
    from engine.graph.bridges import forward_to

    span = gap * (n_targets - 1)
    h = n_candidates // 2
    long = bounds[(bounds[:, 1] - bounds[:, 0]) > span + n_candidates]
    now, full = [], []
    for r in range(repeats + 1):
        u = long[rng.integers(len(long))]
        f0 = int(rng.integers(u[0] + h, u[1] - span - h))
        cands = [np.unique(g.labels_[f - h: f + h]) for f in range(f0, f0 + span + 1, gap)]
        t = time.perf_counter()
        S = [forward_to(mg, a, gap + 1, b) for a, b in zip(cands[:-1], cands[1:])]
        t_now = time.perf_counter() - t
        t = time.perf_counter()
        R = [mg.forward(a, gap + 1)[:, b] for a, b in zip(cands[:-1], cands[1:])]
        t_full = time.perf_counter() - t
        assert all(np.array_equal(x, y) for x, y in zip(S, R)), "forward_to differs from the full recursion"
        if r:
            now.append(t_now), full.append(t_full)
    return now, full


def main():
    import sys

    if len(sys.argv) == 6 and sys.argv[1] == "--child":
        return _child(sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5] == "1")
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", choices=("synthetic", "standin"), default=None)
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--repeats", type=int, default=21, help="warm queries per K (>= 20 for the issue's figures)")
    ap.add_argument("--cold-runs", type=int, default=5, help="fresh processes per query and K")
    ap.add_argument("--synthesis-repeats", type=int, default=5)
    ap.add_argument("--states", type=int, nargs="+", default=[1000, 5000])
    ap.add_argument("--frames", type=int, default=PAPER_FRAMES, help="frames of the stand-in (default: the paper's)")
    ap.add_argument("--no-tangent", action="store_true", help="skip the TangentFrames fit")
    ap.add_argument("--reuse", default=None, help="folder keeping fitted state graphs between runs")
    Harness.add_arguments(ap)
    args = ap.parse_args()
    bench = Harness("bench_states", args)

    import tempfile
    from pathlib import Path

    from engine.files.atomic import atomic_write
    from engine.files.persist import dump_estimator, load_estimator, read_npz
    from engine.graph.states import StateGraph, StateGraphConnectivityWarning
    from engine.manifold.tangent import TangentFrames

    source = args.source
    if source is None:
        try:
            import engine.talker.synthetic  # noqa: F401
            source = "synthetic"
        except ImportError:
            source = "standin"
    t = time.perf_counter()
    if source == "synthetic":
        Fy, Fx, Fxv, b, corpus = synthetic(args.preset)
        print(f"data: engine.talker.synthetic preset {args.preset!r} through shape/dynamics/embedding: "
              f"{len(Fy)} frames x {corpus.frames.shape[1]} coordinates, {len(b)} utterances "
              f"({time.perf_counter() - t:.1f} s to build)")
        tag = f"synthetic_{args.preset}"
    else:
        Fy, Fx, Fxv, b, _ = standin(args.frames)
        print(f"data: STAND-IN (paraboloid sheet of speech-like opening trajectories), {len(Fy)} frames, "
              f"{len(b)} utterances (engine.talker.synthetic not used)")
        tag = f"standin_{args.frames}"
    print(f"{os.cpu_count()} cores; no query calls BLAS")

    if not args.no_tangent:
        tan, _ = bench.measure("TangentFrames.fit", lambda: TangentFrames().fit(Fy, b, np.asarray(Fx[:, 0], np.float64),
                                                                                rate=60.0), cpu=True)
        print(f"  k = {tan.n_neighbors_}")
        print("  classes " + ", ".join(f"{k} {100 * v:.1f}%" for k, v in tan.class_proportions().items()))

    tmp = tempfile.TemporaryDirectory()
    keep = Path(args.reuse) if args.reuse else Path(tmp.name)
    keep.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(1)
    for K in args.states:
        saved = keep / f"states_{tag}_K{K}.npz"
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", StateGraphConnectivityWarning)
            print()
            if saved.is_file():
                g, _ = bench.measure(f"StateGraph loaded K={K}", cpu=True, file=saved.name,
                                     fn=lambda saved=saved: load_estimator(StateGraph, read_npz(saved), "states"))
            else:
                g, _ = bench.measure(f"StateGraph.fit K={K}", lambda K=K: StateGraph(n_states=K).fit(Fy, b), cpu=True)
                with atomic_write(saved) as part:
                    np.savez(part, **dump_estimator(g, "states"))
        print("  " + g.connectivity_report().replace("\n", "\n  "))
        for w in caught:
            print(f"  warning: {w.message}")
        big = np.flatnonzero(g.scc_labels_ == g.largest_scc_)

        print(f"  future+past hemispheres, cold: {_cold(saved, 'hemisphere', args.cold_runs, bench, K)}")
        g.hemispheres(int(big[0]))  # build the cached csr forms once
        times, cpu = [], []
        for s in rng.choice(big, size=args.repeats):
            t, c = time.perf_counter(), time.process_time()
            g.hemispheres(int(s))
            times.append(time.perf_counter() - t), cpu.append(time.process_time() - c)
        print(f"  future+past hemispheres, warm: {_stats(times, cpu)} states; {_load_avg()}")
        bench.figure(f"K={K} hemisphere, warm", times, cold=False, headline=True, cpu_median_s=float(np.median(cpu)))

        print(f"  10-state path (9 min_path legs), cold: {_cold(saved, 'path', args.cold_runs, bench, K)}")
        times, cpu, hops, before = [], [], [], []
        for _ in range(args.repeats):
            way = rng.choice(big, size=10, replace=False)
            t, c = time.perf_counter(), time.process_time()
            path = _ten_state_path(g, way)
            times.append(time.perf_counter() - t), cpu.append(time.process_time() - c)
            hops.append(len(path) - 1)
            t = time.perf_counter()
            assert np.array_equal(_ten_state_path_before(g, way), path), "min_path differs from the tree path"
            before.append(time.perf_counter() - t)
        print(f"  10-state path (9 min_path legs), warm: {_stats(times, cpu)} paths (median {int(np.median(hops))} "
              f"hops per path); the same paths by a whole breadth-first search per leg (before), alternating: "
              f"{_stats(before)}; {_load_avg()}")
        bench.figure(f"K={K} 10-state path, warm", times, cold=False, headline=True, cpu_median_s=float(np.median(cpu)))
        bench.figure(f"K={K} 10-state path by whole BFS (before), warm", before, cold=False)

        if args.synthesis_repeats > 0:
            mg, setup = _max_product_graph(g)
            now, full = _synthesis_path(mg, g, np.asarray(b), rng, args.synthesis_repeats)
            print(f"  synthesis state path (10 targets 6 frames apart, exact-length Viterbi per gap), warm: "
                  f"{_stats(now)}; the full recursion over every edge, same targets: {_stats(full)} "
                  f"(graph set-up {setup * 1e3:.0f} ms, once); {_load_avg()}")
            bench.figure(f"K={K} synthesis state path, warm", now, cold=False)
            bench.figure(f"K={K} synthesis state path by full recursion, warm", full, cold=False)
            now, full = _lattice_scores(mg, g, np.asarray(b), rng, args.synthesis_repeats)
            print(f"  phone lattice of synthesize --text (10 targets 6 frames apart, <= 8 candidate states each), "
                  f"warm: {_stats(now)}; the full recursion, same candidates: {_stats(full)}; {_load_avg()}")
            bench.figure(f"K={K} phone lattice, warm", now, cold=False)
            bench.figure(f"K={K} phone lattice by full recursion, warm", full, cold=False)
        tracemalloc.start()
        g.hemispheres(int(big[0]))
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
        print(f"  peak traced memory of one hemisphere query {peak:.2f} MiB; max RSS {peak_rss_mb():.1f} MiB")
    tmp.cleanup()
    bench.finish()


if __name__ == "__main__":
    main()

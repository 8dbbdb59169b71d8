"""Benchmark: build the manifold on the synthetic talker and print wall time and peak memory per stage.

Usage: python benchmarks/bench_build.py [--preset paper|default|small] [--method pca|mds] [--landmarks L]

Target (issue 2): the paper-scale preset (28,833 x 12,784) builds in well under a minute
on two cores with a few GB of memory.
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from _harness import Harness


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--method", default="pca")
    ap.add_argument("--landmarks", type=int, default=None)
    Harness.add_arguments(ap)
    args = ap.parse_args()
    bench = Harness("bench_build", args)

    def stage(name, fn, rows):
        out, m = bench.measure(name, fn, cold=True)
        rows.append((name, m.first, m.peak_traced_mib))
        return out

    from engine.graph.states import StateGraph
    from engine.manifold.dynamics import DynamicFeatures
    from engine.manifold.embedding import Embedding
    from engine.manifold.shape import ShapeSpace
    from engine.manifold.tangent import TangentFrames
    from engine.talker.synthetic import load_synthetic

    rows = []
    corpus = stage("corpus (cache/generate)", lambda: load_synthetic(preset=args.preset), rows)
    print(f"corpus: {corpus.n_frames} frames x {corpus.frames.shape[1]} coordinates "
          f"({corpus.n_points} points), {corpus.frames.nbytes / 2**20:.0f} MiB float32")
    t0 = time.perf_counter()
    shape = stage("shape space X", lambda: ShapeSpace().fit(corpus.frames), rows)
    Fx = stage("project F^x", lambda: shape.transform(corpus.frames), rows)
    b = corpus.bounds
    G = stage("dynamic features G",
              lambda: DynamicFeatures().fit(Fx, b).transform(Fx, b), rows)
    emb = stage(f"embedding Y ({args.method})",
                lambda: Embedding(method=args.method, n_landmarks=args.landmarks).fit(G), rows)
    Fy = emb.embedding_
    from engine.recordings.kinematics import lip_aperture

    stage("tangent frames", lambda: TangentFrames().fit(Fy, b, lip_aperture(corpus), rate=corpus.rate), rows)
    stage("state graph", lambda: StateGraph().fit(Fy, b), rows)
    total = time.perf_counter() - t0
    bench.figure("TOTAL build (excluding corpus generation)", total, cold=True, headline=True,
                 peak_traced_mib=max(r[2] for r in rows[1:]))
    bench.fact(frames=corpus.n_frames, coordinates=int(corpus.frames.shape[1]),
               shape_components=int(shape.n_components_))
    print(f"\nshape: {shape.n_components_} components hold {100 * shape.recovered_ratio_[shape.n_components_ - 1]:.2f}%"
          f"; Y first 3 dims hold {100 * emb.recovered_ratio_[2]:.1f}% of recovered variance; "
          f"{emb.n_passes_} passes over D")
    print(f"(numpy {np.__version__})")
    bench.finish()


if __name__ == "__main__":
    main()

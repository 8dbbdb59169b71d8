"""The paper-scale build against its floor: the same GEMMs and streamed reads and nothing else (issue 13 item 5).

The *floor* of a build is the work it cannot avoid: with the paper's corpus (28,833
frames x 12,780 coordinates, ``load_synthetic(preset="paper")``) and the build's own
parameters it is

* shape space: one streamed read of F for the mean, ``n_iter + 1`` products ``F X`` and
  ``n_iter + 1`` products ``F^T Y`` with the range finder's ``k + p`` columns, one read
  for the total sum of squares and one product ``F V^T`` for F^x (m columns): float32
  GEMMs over 4,096-row blocks of F, with every BLAS thread;
* embedding: for each of the build's passes over the distance matrix (``n_passes_``),
  every block of rows of D formed by one GEMM on augmented coordinates (N x (2m + 2)
  times (2m + 2) x L), clipped and square-rooted, and multiplied by the range finder's r
  columns.

No QR, no SVD, no tangent frames, states or validation: those are the build's
overhead above the floor (small at this size). The widths (k + p, m, r, L, passes)
are read from a build of the same corpus, so the floor does exactly the GEMMs the
build does.

The benchmark runs build and floor as *pairs*, each in a fresh process (cold: imports
and loading the corpus from the cache are not timed), alternating so that both see
the same load, and prints each pair's wall times and ratio build / floor, then min
and median of the ratios and of both walls (goal: ratio <= 2), the load average and
the BLAS kernel.

Usage::

    python benchmarks/floor_build.py [--pairs 3] [--preset paper]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import blas_kernel  # noqa: E402

ROWS = 4096  # rows of F per product block


def floor(F, *, r_shape: int, n_iter: int, m: int, r_emb: int, n_passes: int, L: int | None = None,
          block_bytes: int = 96 * 2**20, seed: int = 0) -> dict:
    """Do the build's necessary GEMMs and reads on F (N, C) float32; return seconds per part."""
    import numpy as np

    rng = np.random.default_rng(seed)
    N, C = F.shape
    out = {}
    t = time.perf_counter()
    mean = np.zeros(C, np.float64)
    for s in range(0, N, ROWS):
        mean += F[s:s + ROWS].sum(axis=0, dtype=np.float64)
    X = rng.standard_normal((C, r_shape)).astype(np.float32)
    Y = np.empty((N, r_shape), np.float32)
    for _ in range(n_iter + 1):
        for s in range(0, N, ROWS):
            Y[s:s + ROWS] = F[s:s + ROWS] @ X
        Z = np.zeros((C, r_shape), np.float32)
        for s in range(0, N, ROWS):
            Z += F[s:s + ROWS].T @ Y[s:s + ROWS]
    mean32 = mean.astype(np.float32) / N
    total = 0.0
    for s in range(0, N, ROWS):
        d = F[s:s + ROWS] - mean32
        total += float(np.einsum("ij,ij->", d, d, dtype=np.float64))
    V = rng.standard_normal((C, m)).astype(np.float32)
    Fx = np.empty((N, m), np.float32)
    for s in range(0, N, ROWS):
        Fx[s:s + ROWS] = F[s:s + ROWS] @ V
    out["shape"] = time.perf_counter() - t

    t = time.perf_counter()
    G = np.hstack([Fx, np.diff(Fx, axis=0, prepend=Fx[:1])]).astype(np.float32)
    L = N if L is None else L
    cols = G[:L]
    sq = np.einsum("ij,ij->i", G, G)
    rows_aug = np.hstack([G, sq[:, None], np.ones((N, 1), np.float32)]).astype(np.float32)
    cols_aug_t = np.ascontiguousarray(np.hstack([-2.0 * cols, np.ones((L, 1), np.float32), sq[:L, None]]).T)
    block = max(16, min(N, block_bytes // (4 * L)))
    Xe = rng.standard_normal((L, r_emb)).astype(np.float32)
    Ye = np.empty((N, r_emb), np.float32)
    for _ in range(n_passes):
        for s in range(0, N, block):
            D = rows_aug[s:s + block] @ cols_aug_t
            np.maximum(D, 0.0, out=D)
            np.sqrt(D, out=D)
            Ye[s:s + block] = D @ Xe
    out["embedding"] = time.perf_counter() - t
    out["total"] = out["shape"] + out["embedding"]
    out["checksum"] = float(total + Ye[:1].sum() + Z[:1].sum())  # the results are used
    return out


def _corpus(preset):
    from engine.synthetic import load_synthetic

    return load_synthetic(preset=preset)


def run_build(preset) -> dict:
    import warnings

    from engine.manifold import Manifold

    corpus = _corpus(preset)
    load0 = os.getloadavg()[0]
    c0, t = time.process_time(), time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = Manifold().fit(corpus)
    wall, cpu = time.perf_counter() - t, time.process_time() - c0
    sh, emb = m.shape_, m.embedding_
    widths = {"r_shape": int(min(sh.max_components, corpus.n_frames - 1, corpus.frames.shape[1])) + 10,
              "n_iter": int(sh.n_iter), "m": int(sh.n_components_), "r_emb": int(emb.n_components) + int(emb.oversample),
              "n_passes": int(emb.n_passes_), "L": int(emb.reference_.shape[0])}
    return {"wall_s": wall, "cpu_s": cpu, "stages": m.timings_, "widths": widths, "load": load0,
            "shape": list(corpus.frames.shape), "blas": blas_kernel()}


def run_floor(preset, widths) -> dict:
    import numpy as np

    F = np.ascontiguousarray(_corpus(preset).frames, dtype=np.float32)
    load0 = os.getloadavg()[0]
    c0, t = time.process_time(), time.perf_counter()
    parts = floor(F, **widths)
    wall, cpu = time.perf_counter() - t, time.process_time() - c0
    return {"wall_s": wall, "cpu_s": cpu, "parts": parts, "load": load0}


def _child(args) -> dict:
    out = subprocess.run([sys.executable, os.path.abspath(__file__), *args], capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(f"{' '.join(args)} failed:\n{out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--child", choices=("build", "floor"), help=argparse.SUPPRESS)
    ap.add_argument("--widths", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child == "build":
        print(json.dumps(run_build(args.preset)))
        return 0
    if args.child == "floor":
        print(json.dumps(run_floor(args.preset, json.loads(args.widths))))
        return 0
    builds, floors, ratios = [], [], []
    for i in range(args.pairs):
        b = _child(["--child", "build", "--preset", args.preset])
        f = _child(["--child", "floor", "--preset", args.preset, "--widths", json.dumps(b["widths"])])
        builds.append(b["wall_s"])
        floors.append(f["wall_s"])
        ratios.append(b["wall_s"] / f["wall_s"])
        st = ", ".join(f"{k} {v:.1f}" for k, v in b["stages"].items())
        print(f"pair {i}: build {b['wall_s']:.1f} s wall / {b['cpu_s']:.1f} s CPU ({st}); floor {f['wall_s']:.1f} s "
              f"wall / {f['cpu_s']:.1f} s CPU (shape {f['parts']['shape']:.1f}, embedding "
              f"{f['parts']['embedding']:.1f}); ratio {ratios[-1]:.2f}; load average {b['load']:.1f} / "
              f"{f['load']:.1f}", flush=True)
    med = statistics.median
    print(f"corpus {b['shape'][0]} x {b['shape'][1]}; widths {b['widths']}")
    print(f"build/floor over {len(ratios)} pairs: min {min(ratios):.2f}, median {med(ratios):.2f} (goal <= 2); "
          f"build min {min(builds):.1f} s, median {med(builds):.1f} s; floor min {min(floors):.1f} s, median "
          f"{med(floors):.1f} s; {os.cpu_count()} cores\nBLAS: {b['blas']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

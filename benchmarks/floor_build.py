"""The paper-scale build against its floor: the same GEMMs and streamed reads and nothing else (issue 13 item 5).

The *floor* of a build is the work it cannot avoid: with the paper's corpus (28,833
frames x 12,780 coordinates, ``load_synthetic(preset="paper")``) and the build's own
parameters it is

* shape space: one streamed read of F for the mean, ``n_iter + 1`` products ``F X`` and
  ``n_iter + 1`` products ``F^T Y`` with the range finder's ``k + p`` columns, one read
  for the total sum of squares and one product ``F V^T`` for F^x (m columns): float32
  GEMMs over 4,096-row blocks of F, with every BLAS thread;
* embedding: for each of the build's passes over the distance matrix (``n_passes_``),
  every 8 MiB block of rows of D formed by one GEMM on augmented coordinates (N x (2m + 2)
  times (2m + 2) x L), clipped and square-rooted, and multiplied by the range finder's r
  columns, one block per core at a time on one BLAS thread each (the fastest way found:
  two-thread GEMMs on shared cores took up to 1.8x as long).

No QR, no SVD, no tangent frames, states or validation: those are the build's
overhead above the floor (small at this size). The widths (k + p, power iterations, m, r, L, passes)
are read from a build of the same corpus, so the floor does exactly the GEMMs the
build does.

This script runs the floor alone (one fresh process, corpus loading not timed) and
prints its seconds, GFLOP and bytes streamed. ``benchmarks/bench_build_floor.py`` runs
it beside the build in paired, alternating fresh processes and reports the ratio.

Usage::

    python benchmarks/floor_build.py [--preset paper] [--widths '{"r_shape": 110, ...}']
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import blas_kernel, peak_rss_mb  # noqa: E402

ROWS = 4096  # rows of F per product block


def floor(F, *, r_shape: int, n_iter: int, m: int, r_emb: int, n_passes: int, L: int | None = None,
          block_bytes: int = 8 * 2**20, seed: int = 0) -> dict:
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

    def one(s):
        D = rows_aug[s:s + block] @ cols_aug_t
        np.maximum(D, 0.0, out=D)
        np.sqrt(D, out=D)
        Ye[s:s + block] = D @ Xe

    # the fastest way found: one block per core at a time, each on one BLAS thread
    from concurrent.futures import ThreadPoolExecutor

    from engine.threads import one_blas_thread

    with one_blas_thread(), ThreadPoolExecutor(os.cpu_count() or 1) as ex:
        for _ in range(n_passes):
            list(ex.map(one, range(0, N, block)))
    out["embedding"] = time.perf_counter() - t
    out["total"] = out["shape"] + out["embedding"]
    out["checksum"] = float(total + Ye[:1].sum() + Z[:1].sum())  # the results are used
    return out


#: the widths of the build the issue measured (951 GFLOP): 100 + 10 shape columns and 3
#: power iterations, 10 + 10 embedding columns and 6 passes over D; m and L come from
#: the corpus (the kept components and the frames are the same whatever the widths)
ISSUE_WIDTHS = {"r_shape": 110, "n_iter": 3, "r_emb": 20, "n_passes": 6}


def work(N, C, *, r_shape, n_iter, m, r_emb, n_passes, L=None, **_) -> dict:
    """GFLOP of the floor's GEMMs and GB it streams from F, for an (N, C) corpus."""
    L = N if L is None else L
    shape_cols = 2 * (n_iter + 1) * r_shape + m
    gflop = (2.0 * N * C * shape_cols + n_passes * 2.0 * N * L * ((2 * m + 2) + r_emb)) / 1e9
    reads = 2 * (n_iter + 1) + 3  # the mean, the range finder's products, the total, F^x
    return {"gflop": gflop, "gb_read": reads * N * C * 4 / 1e9}


def _corpus(preset):
    from engine.talker.synthetic import load_synthetic

    return load_synthetic(preset=preset)


def run_floor(preset, widths) -> dict:
    """Load the corpus, then time :func:`floor` (wall and CPU seconds) in this process."""
    import numpy as np

    F = np.ascontiguousarray(_corpus(preset).frames, dtype=np.float32)
    load0 = os.getloadavg()[0]
    c0, t = time.process_time(), time.perf_counter()
    parts = floor(F, **widths)
    wall, cpu = time.perf_counter() - t, time.process_time() - c0
    return {"wall_s": wall, "cpu_s": cpu, "parts": parts, "load": load0, "work": work(*F.shape, **widths),
            "max_rss_mib": peak_rss_mb()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--widths", help="JSON of floor()'s widths (default: the issue's, with m=30 and L=N)")
    ap.add_argument("--json", action="store_true", help="print one JSON line (for bench_build_floor.py)")
    args = ap.parse_args(argv)
    widths = json.loads(args.widths) if args.widths else dict(ISSUE_WIDTHS, m=30)
    out = run_floor(args.preset, widths)
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"floor {out['wall_s']:.2f} s wall / {out['cpu_s']:.2f} s CPU (shape {out['parts']['shape']:.2f}, "
          f"embedding {out['parts']['embedding']:.2f}); {out['work']['gflop']:.0f} GFLOP, "
          f"{out['work']['gb_read']:.1f} GB read from F; widths {widths}; load average {out['load']:.1f}; "
          f"max RSS {out['max_rss_mib']:.0f} MiB\nBLAS: {blas_kernel()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

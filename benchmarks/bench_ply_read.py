"""Benchmark: reading PLY files whose face lists vary in length (or are empty).

Usage: python benchmarks/bench_ply_read.py [--mb 10] [--repeats 5] [--impl PATH] [--timeout 180]

Cases (each about ``--mb`` MB, written to a temporary folder):

* ``bin-empty``   binary, every face list empty (the bad-input campaign's file: 90 s, 1.7 GB before)
* ``bin-mixed``   binary, triangles and quads mixed at random (a real polygon mesh)
* ``bin-tri-then-empty`` binary, one triangle then empty lists (defeats a constant-length fast path)
* ``ascii-mixed`` ASCII, triangles and quads mixed
* ``ascii-empty`` ASCII, every face list empty

Each case runs in a fresh process: the first read is cold (imports and page cache
warm, code paths not), then ``--repeats`` warm reads; min and median of the warm
reads, and the process's peak resident memory, are printed. ``--impl`` reads with
another copy of ``engine/io/readers/meshfile.py`` (e.g. the previous commit's, for a before /
after comparison). A reader error (these files' empty faces are refused) counts as
a completed read: what is timed is how long it takes to decide.
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASES = ("bin-empty", "bin-mixed", "bin-tri-then-empty", "ascii-mixed", "ascii-empty")


def make(case: str, folder: Path, mb: float) -> Path:
    import numpy as np

    rng = np.random.default_rng(0)
    n_v = 1000
    V = rng.normal(size=(n_v, 3)).astype("<f4")
    binary = case.startswith("bin")
    budget = int(mb * 2**20)
    if case.endswith("empty"):
        n = budget // (1 if binary else 2)
        sizes = np.zeros(n, np.int64)
        if case == "bin-tri-then-empty":
            sizes[0] = 3
    else:
        n = budget // (15 if binary else 20)
        sizes = rng.choice([3, 4], size=n)
    head = (f"ply\nformat {'binary_little_endian' if binary else 'ascii'} 1.0\nelement vertex {n_v}\n"
            "property float x\nproperty float y\nproperty float z\n"
            f"element face {len(sizes)}\nproperty list uchar int vertex_indices\nend_header\n").encode()
    items = rng.integers(0, n_v, size=int(sizes.sum()))
    p = folder / f"{case}.ply"
    with open(p, "wb") as fh:
        fh.write(head)
        if binary:
            fh.write(V.tobytes())
            out = bytearray()
            ends = np.cumsum(sizes)
            starts = ends - sizes
            for k, s, e in zip(sizes.tolist(), starts.tolist(), ends.tolist()):
                out += bytes([k]) + items[s:e].astype("<i4").tobytes()
            fh.write(bytes(out))
        else:
            fh.write("".join(f"{a:.6f} {b:.6f} {c:.6f}\n" for a, b, c in V.tolist()).encode())
            ends = np.cumsum(sizes)
            fh.write("".join(" ".join([str(k), *map(str, items[e - k:e].tolist())]) + "\n"
                             for k, e in zip(sizes.tolist(), ends.tolist())).encode())
    return p


def one(path: str, impl: str | None, repeats: int) -> dict:
    sys.path.insert(0, str(ROOT))
    if impl:
        spec = importlib.util.spec_from_file_location("meshfile_under_test", impl)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    else:
        from engine.io.readers import meshfile as mod
    times, outcome = [], ""
    for _ in range(1 + repeats):
        t = time.perf_counter()
        try:
            V, F = mod.read_ply(path)
            outcome = f"{len(V)} vertices, {0 if F is None else len(F)} triangles"
        except ValueError as exc:
            outcome = f"refused: {str(exc)[len(path) + 2:][:70]}"
        times.append(time.perf_counter() - t)
    from _common import blas_kernel, peak_rss_mb

    return {"cold_s": times[0], "warm_min_s": min(times[1:]) if repeats else float("nan"),
            "warm_median_s": statistics.median(times[1:]) if repeats else float("nan"),
            "peak_rss_mb": peak_rss_mb(), "outcome": outcome, "times": times,
            "blas": blas_kernel()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mb", type=float, default=10.0)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--impl", default=None, help="path of another meshfile.py to time instead")
    ap.add_argument("--timeout", type=float, default=180.0)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--_one", nargs=2, help=argparse.SUPPRESS)
    from _harness import Harness

    Harness.add_arguments(ap)
    args = ap.parse_args()
    if args._one:
        print(json.dumps(one(args._one[0], args._one[1] or None, args.repeats)))
        return 0
    import os

    from _common import run_child_json

    bench = Harness("bench_ply_read", args)
    print(f"load average {os.getloadavg()[0]:.2f}; reader {args.impl or 'engine/io/readers/meshfile.py'}")
    with tempfile.TemporaryDirectory() as d:
        for case in args.cases.split(","):
            p = make(case, Path(d), args.mb)
            cmd = [sys.executable, __file__, "--repeats", str(args.repeats), "--_one", str(p), args.impl or ""]
            try:
                res = run_child_json(cmd, timeout=args.timeout)
            except subprocess.TimeoutExpired:
                print(f"{case:20s} {p.stat().st_size / 2**20:6.1f} MB  did not finish in {args.timeout:g} s")
                continue
            except SystemExit as failed:  # the child's command and the end of its stderr
                print(f"{case:20s} failed: {str(failed).strip()[-300:]}")
                continue
            print(f"{case:20s} {p.stat().st_size / 2**20:6.1f} MB  cold {res['cold_s']:7.3f} s  warm min "
                  f"{res['warm_min_s']:7.3f} s  median {res['warm_median_s']:7.3f} s  peak RSS "
                  f"{res['peak_rss_mb']:7.0f} MB  {res['outcome']}")
            bench.figure(f"read {case}", res["times"], cold=True, first_is_separate=True, show=False,
                         peak_rss_mib=res["peak_rss_mb"], headline=case == "bin-mixed",
                         file_mb=p.stat().st_size / 2**20, outcome=res["outcome"])
    bench.finish()
    return 0


if __name__ == "__main__":
    sys.exit(main())

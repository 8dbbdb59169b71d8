"""Benchmark: the inverse map's cold start, and `lipspace synthesize --text` end to end.

Usage: python benchmarks/bench_inverse_cold.py [--manifold FILE] [--repeat 3] [--cache-dir DIR]

Issue 9 item 3: the first Y -> X query on the default manifold cost 18-60 s because
scipy factorises every simplex's barycentric transform one by one (one LAPACK call
each) on first use. The inverse map now computes all of them in one numpy batch.

Printed, each as min / median over ``--repeat`` fresh processes (so every figure is a
cold figure: a new process pays the Delaunay set-up and the transforms once):

* ``stage`` rows: load the manifold, Delaunay tetrahedralisation, the transforms by the
  old path (scipy's own, ``tri.transform``) and by the new one
  (``engine.manifold.inverse.barycentric_transforms``), measured side by side in the same
  process; the first and a second (warm) query of 79 state points;
* ``command`` rows: ``lipspace synthesize --manifold FILE --text "bob meets mum"`` as a
  whole process (imports, load, synthesis, inverse map, writing the CSV), wall time and
  peak RSS; the first run after the manifold file was written is the cold one (file
  cache may still be warm: the build just wrote it).

The BLAS kernel in use is printed (threadpoolctl): OPENBLAS_CORETYPE / OPENBLAS_L2_SIZE,
when set, slow small LAPACK calls, which is what made the old path slow.
"""
from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import run_child_json  # noqa: E402
from _harness import Harness  # noqa: E402

_STAGES = r"""
import json, sys, time
import numpy as np
t0 = time.perf_counter()
from engine.manifold.model import Manifold
from engine.manifold.inverse import InverseMap, barycentric_transforms, QHULL_OPTIONS
from scipy.spatial import Delaunay
out = {"import": time.perf_counter() - t0}
t = time.perf_counter(); m = Manifold.load(sys.argv[1]); out["load manifold"] = time.perf_counter() - t
inv = InverseMap(n_dims=3)
Fy3 = np.asarray(m.Fy_[:, :3], dtype=np.float64)
t = time.perf_counter(); tri = Delaunay(inv._check_Y(Fy3, 3) - Fy3.mean(0), qhull_options=QHULL_OPTIONS)
out["Delaunay (qhull)"] = time.perf_counter() - t
t = time.perf_counter(); T_old = tri.transform
out["transforms, old path (scipy per simplex)"] = time.perf_counter() - t
t = time.perf_counter(); T_new = barycentric_transforms(tri.points, tri.simplices)
out["transforms, new path (numpy batch)"] = time.perf_counter() - t
out["simplices"] = int(tri.simplices.shape[0])
t = time.perf_counter(); inv.fit(m.Fy_, m.Fx_)
out["InverseMap.fit (qhull + batch transforms)"] = time.perf_counter() - t
q = m.states_.centroids_[:79, :3]
t = time.perf_counter(); inv.transform(q); out["first query, 79 points (cold)"] = time.perf_counter() - t
t = time.perf_counter(); inv.transform(q); out["second query, 79 points (warm)"] = time.perf_counter() - t
print(json.dumps(out))
"""


def _child_peak_mb():
    return resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--manifold", help="manifold file (default: build the default talker into a temp dir)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cache-dir", help="LIPSPACE_CACHE_DIR for the talker (default: the user cache)")
    Harness.add_arguments(ap)
    args = ap.parse_args(argv)
    bench = Harness("bench_inverse_cold", args)
    env = dict(os.environ)
    if args.cache_dir:
        env["LIPSPACE_CACHE_DIR"] = args.cache_dir
    lipspace = [sys.executable, "-m", "app.cli"]
    with tempfile.TemporaryDirectory() as tmp:
        man = args.manifold
        if man is None:
            man = str(Path(tmp) / "talker.npz")
            t = time.perf_counter()
            subprocess.run(lipspace + ["build", "-o", man, "--quiet"], check=True, env=env, cwd=ROOT)
            print(f"built the default talker's manifold in {time.perf_counter() - t:.1f} s", flush=True)
        stages = {}
        for _ in range(args.repeat):
            for k, v in run_child_json([sys.executable, "-c", _STAGES, man], env=env, cwd=ROOT).items():
                stages.setdefault(k, []).append(v)
        n_simp = stages.pop("simplices")[0]
        print(f"\nstages, fresh process each ({n_simp} simplices), min / median of {args.repeat}:")
        for k, v in stages.items():
            print(f"  {k:<46} {min(v):8.3f} s  {np.median(v):8.3f} s")
            bench.figure(k, v, cold=True, show=False, headline=k == "first query, 79 points (cold)")
        old, new = (np.array(stages[k]) for k in ("transforms, old path (scipy per simplex)",
                                                   "transforms, new path (numpy batch)"))
        ratio = old / new
        print(f"  old / new transforms, pair by pair: min {ratio.min():.1f}x  median {np.median(ratio):.1f}x")
        bench.figure("old / new transforms, pair by pair", list(ratio), "x", show=False)
        bench.fact(simplices=n_simp)

        cmd = lipspace + ["synthesize", "--manifold", man, "--text", "bob meets mum",
                          "-o", str(Path(tmp) / "t.csv"), "--quiet", "--force"]  # every run replaces t.csv
        walls = []
        for _ in range(args.repeat):
            t = time.perf_counter()
            subprocess.run(cmd, check=True, env=env, cwd=ROOT, capture_output=True)
            walls.append(time.perf_counter() - t)
        print(f"\ncommand: lipspace synthesize --manifold {Path(man).name} --text 'bob meets mum' -o t.csv")
        print(f"  first run (cold process)                      {walls[0]:8.3f} s")
        print(f"  all runs, min / median of {args.repeat}                  {min(walls):8.3f} s  "
              f"{np.median(walls):8.3f} s   (goal < 3 s)")
        print(f"  peak RSS of the largest child process          {_child_peak_mb():8.0f} MiB")
        bench.figure("lipspace synthesize --text, whole process", walls, cold=True, first_is_separate=False,
                     peak_rss_mib=_child_peak_mb(), headline=True, show=False)
    bench.finish()


if __name__ == "__main__":
    main()

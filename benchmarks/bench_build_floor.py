"""The paper-scale build against its floor, paired and alternated (issue 13 item 5; goal: build <= 2x floor).

Each pair runs the build (``Manifold().fit`` on ``load_synthetic(preset="paper")``) and
the floor (``benchmarks/floor_build.py``: exactly the build's GEMMs and streamed reads)
in fresh processes, one after the other; even pairs run the build first, odd pairs the
floor first, so that a change of load between the two touches both. Imports and loading
the cached corpus are not timed (the corpus cache is filled before the first pair).

Two floors are run in every pair:

* **own**: the floor with the widths the build used this time (range-finder columns,
  power iterations, passes over D), read from the fitted manifold: the ratio
  build / own floor is the build's overhead above its own GEMMs;
* **issue**: the floor of the build the issue measured (110 shape columns and 3 power
  iterations, 20 embedding columns and 6 passes over D, about 951 GFLOP): the ratio
  build / issue floor is the goal as the issue states it.

Printed: every pair's walls, CPU seconds, stage times and ratios; then min and median
over pairs of both ratios and of the walls; the build's stages against the floor's parts
(the shape space and the embedding have a floor; the dynamic features, the tangent frames,
the state graph and the inverse map have none, so their seconds are what the build pays
above it); peak RSS of each process; the load average before and after; the BLAS kernel.

``--choice`` also times, in the build's process after the fit, the synthesis choice that
``lipspace build`` measures and stores (:func:`engine.synthesis.method_choice.fit_choice`);
it is printed beside the build, never counted in the ratios (it has no GEMM floor).

Usage::

    python benchmarks/bench_build_floor.py [--pairs 3] [--preset paper] [--no-issue-floor] [--choice]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
for p in (ROOT, HERE):
    if p not in sys.path:
        sys.path.insert(0, p)
from _common import blas_kernel, peak_rss_mb, run_child_json  # noqa: E402
from _harness import Harness  # noqa: E402
from floor_build import ISSUE_WIDTHS, work  # noqa: E402


def run_build(preset, choice=False) -> dict:
    """Load the corpus, then time ``Manifold().fit`` in this process (and ``fit_choice`` after it with
    ``choice``); report the widths it used."""
    import warnings

    from engine.manifold.model import Manifold
    from engine.talker.synthetic import load_synthetic

    corpus = load_synthetic(preset=preset)
    load0 = os.getloadavg()[0]
    c0, t = time.process_time(), time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = Manifold().fit(corpus)
    wall, cpu = time.perf_counter() - t, time.process_time() - c0
    choice_s = None
    if choice:
        from engine.synthesis.method_choice import fit_choice

        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit_choice(m)
        choice_s = time.perf_counter() - t
    sh, emb = m.shape_, m.embedding_
    N, C = corpus.frames.shape
    widths = {"r_shape": int(getattr(sh, "n_range_", min(sh.max_components, N - 1, C) + 10)),  # older trees
              "n_iter": int(getattr(sh, "n_iter_", sh.n_iter)), "m": int(sh.n_components_),
              "r_emb": int(getattr(emb, "n_range_", emb.n_components + emb.oversample)),
              "n_passes": int(emb.n_passes_), "L": int(emb.reference_.shape[0])}
    return {"wall_s": wall, "cpu_s": cpu, "stages": m.timings_, "widths": widths, "load": load0, "choice_s": choice_s,
            "shape": list(corpus.frames.shape), "blas": blas_kernel(),
            "max_rss_mib": peak_rss_mb()}


def _child(args) -> dict:
    return run_child_json([sys.executable, *args], cwd=ROOT)


def _build(preset, tree=None, choice=False):
    return _child([os.path.abspath(__file__), "--child-build", "--preset", preset, *(["--root", tree] if tree else []),
                   *(["--choice"] if choice else [])])


def _floor(preset, widths):
    return _child([os.path.join(HERE, "floor_build.py"), "--json", "--preset", preset, "--widths", json.dumps(widths)])


def _label(job):
    return job if "build" in job else f"{job} floor"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--no-issue-floor", action="store_true", help="run only the floor of the build's own widths")
    ap.add_argument("--vs-tree", metavar="PATH", help="also build with the engine of another checkout in every pair "
                                                      "(e.g. the previous commit) and report build / that build")
    ap.add_argument("--choice", action="store_true", help="also time the synthesis choice lipspace build measures "
                                                           "after the fit (printed apart, not in the ratios)")
    ap.add_argument("--child-build", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--root", help=argparse.SUPPRESS)
    Harness.add_arguments(ap)
    args = ap.parse_args(argv)
    if args.child_build:
        if args.root:
            sys.path.insert(0, os.path.abspath(args.root))
            for name in [n for n in sys.modules if n == "engine" or n.startswith("engine.")]:
                del sys.modules[name]
        print(json.dumps(run_build(args.preset, args.choice)))
        return 0
    subprocess.run([sys.executable, "-c", f"from engine.talker.synthetic import load_synthetic; "
                    f"load_synthetic(preset={args.preset!r})"], check=True, cwd=ROOT)  # fill the cache
    load_before = os.getloadavg()
    widths = None  # read from pair 0's build, which runs first
    rows = []
    for i in range(args.pairs):
        jobs = (["build", "own"] + ([] if args.no_issue_floor else ["issue"])
                + (["vs-tree build"] if args.vs_tree else []))
        if i % 2 == 1:  # odd pairs: the same runs in reverse order (widths from the previous pair's build)
            jobs.reverse()
        floors, b = {}, None
        for job in jobs:
            if job == "build":
                b = _build(args.preset, choice=args.choice)
                widths = b["widths"]
            elif job == "vs-tree build":
                floors[job] = _build(args.preset, args.vs_tree)
            else:
                w = widths if job == "own" else dict(ISSUE_WIDTHS, m=widths["m"], L=widths["L"])
                floors[job] = _floor(args.preset, w)
        ratios = {k: b["wall_s"] / f["wall_s"] for k, f in floors.items()}
        rows.append((b, floors, ratios))
        st = ", ".join(f"{k} {v:.1f}" for k, v in b["stages"].items())
        fl = "; ".join(f"{_label(k)} {f['wall_s']:.1f} s wall / {f['cpu_s']:.1f} s CPU (" + (
            f"shape {f['parts']['shape']:.1f}, embedding {f['parts']['embedding']:.1f}; "
            f"{f['work']['gflop']:.0f} GFLOP, {f['work']['gb_read']:.1f} GB read" if "parts" in f else
            ", ".join(f"{s} {v:.1f}" for s, v in f["stages"].items())) + f"), ratio {ratios[k]:.2f}"
            for k, f in floors.items())
        ch = f"; then the synthesis choice {b['choice_s']:.1f} s" if b.get("choice_s") is not None else ""
        print(f"pair {i} ({' -> '.join(jobs)}): build {b['wall_s']:.1f} s wall{ch} / "
              f"{b['cpu_s']:.1f} s CPU ({st}), max RSS {b['max_rss_mib']:.0f} MiB; {fl}; load average at start "
              f"{b['load']:.1f} (build) / {floors['own']['load']:.1f} (own floor)", flush=True)
    med = statistics.median
    b0 = rows[-1][0]
    print(f"corpus {b0['shape'][0]} x {b0['shape'][1]}; build widths {b0['widths']}; issue widths "
          f"{dict(ISSUE_WIDTHS, m=b0['widths']['m'], L=b0['widths']['L'])} "
          f"({work(*b0['shape'], **dict(ISSUE_WIDTHS, m=b0['widths']['m'], L=b0['widths']['L']))['gflop']:.0f} GFLOP)")
    builds = [r[0]["wall_s"] for r in rows]
    print(f"build wall over {len(rows)} pairs: min {min(builds):.1f} s, median {med(builds):.1f} s; "
          f"max RSS {max(r[0]['max_rss_mib'] for r in rows):.0f} MiB")
    for k in rows[0][2]:
        rs = [r[2][k] for r in rows]
        fw = [r[1][k]["wall_s"] for r in rows]
        rc = [r[0]["cpu_s"] / r[1][k]["cpu_s"] for r in rows if r[1][k].get("cpu_s")]
        print(f"{_label(k)}: wall min {min(fw):.1f} s, median {med(fw):.1f} s; build / {_label(k)} min "
              f"{min(rs):.2f}, median {med(rs):.2f}{'' if 'build' in k else ' (goal <= 2)'}"
              + (f"; in CPU seconds (less sensitive to other work on the machine) min {min(rc):.2f}, median "
                 f"{med(rc):.2f}" if rc else ""))
    # stage by stage: the floor's parts against the build's stages of the same work, and the stages without a floor
    own = [r[1]["own"] for r in rows if "parts" in r[1]["own"]]
    if own:
        stage = {k: med([r[0]["stages"].get(k, 0.0) for r in rows]) for k in rows[0][0]["stages"]}
        part = {k: med([f["parts"][k] for f in own]) for k in ("shape", "embedding")}
        extra = {k: v for k, v in stage.items() if k not in part}
        print("stage by stage (medians over pairs): " + "; ".join(
            f"{k} {stage.get(k, 0.0):.1f} s against its floor {part[k]:.1f} s ({stage.get(k, 0.0) / part[k]:.2f})"
            for k in part if part[k] > 0)
              + "; without a floor: " + ", ".join(f"{k} {v:.1f} s" for k, v in extra.items())
              + f" (together {sum(extra.values()):.1f} s, "
              f"{100 * sum(extra.values()) / max(med(builds), 1e-9):.0f} % of the build)")
    choices = [r[0]["choice_s"] for r in rows if r[0].get("choice_s") is not None]
    if choices:
        print(f"synthesis choice after the fit (lipspace build stores it; not in the ratios): "
              f"min {min(choices):.1f} s, median {med(choices):.1f} s")
    print(f"load average (1/5/15 min) before {'/'.join(f'{x:.1f}' for x in load_before)}, after "
          f"{'/'.join(f'{x:.1f}' for x in os.getloadavg())}; {os.cpu_count()} cores\nBLAS: {b0['blas']}")
    bench = Harness("bench_build_floor", args, quiet=True)  # the record of the figures printed above
    bench.figure(f"{args.preset} build (fresh process each)", builds, cold=True, headline=True,
                 peak_rss_mib=max(r[0]["max_rss_mib"] for r in rows), show=False)
    for k in rows[0][2]:
        bench.figure(f"build / {_label(k)}", [r[2][k] for r in rows], unit="x", cold=True, headline=k == "own",
                     show=False)
    if choices:
        bench.figure("synthesis choice after the fit", choices, cold=True, show=False)
    bench.fact(corpus_shape=list(b0["shape"]), widths=b0["widths"], child_blas=str(b0["blas"]))
    bench.finish()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

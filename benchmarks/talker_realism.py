"""How real the synthetic talker is to the method: generation time, X scree, Y1-3 variance,
and the tangent classes' agreement with the exact ground truth next to the trivial
Delta F^x_1 rule (engine.talker_report), for the default and the held-out talker.

Run: .venv/bin/python benchmarks/talker_realism.py [--preset default] [--repeats 3] [--skip-heldout]
     [--generation-only] [--tissue]
Generation is timed cold (a fresh process per repeat, no cache) and warm (in-process).
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # the engine, from a checkout

from _common import blas_kernel  # noqa: E402

_COLD = ("import time, json, resource; t=time.perf_counter(); from engine.synthetic import SyntheticTalker; "
         "SyntheticTalker(preset={preset!r}, **{extra!r}).generate(); "
         "print(json.dumps([time.perf_counter()-t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss/1024]))")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="default")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--skip-heldout", action="store_true")
    ap.add_argument("--generation-only", action="store_true", help="time the generation, skip the manifold")
    ap.add_argument("--tissue", action="store_true", help="both talkers with the lip tissue's own variation "
                    "(SyntheticTalker(tissue=True))")
    args = ap.parse_args(argv)
    import os

    from engine.manifold import Manifold
    from engine.lipmodel import CONTROL_NAMES, LipModel
    from engine.synthetic import HELD_OUT_TALKER, PRESETS, SyntheticTalker, speaker_anatomy
    from engine.talker_report import articulation_report, format_articulation, format_realism, talker_realism

    print(f"BLAS: {blas_kernel()}")
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f}")
    root = Path(__file__).resolve().parent.parent
    talkers = [("default talker", {})] + ([] if args.skip_heldout else [("held-out talker", HELD_OUT_TALKER)])
    if args.tissue:
        talkers = [(f"{label} with tissue variation", {**extra, "tissue": True}) for label, extra in talkers]
    for label, extra in talkers:
        cold, peak = [], []
        for _ in range(args.repeats):
            r = subprocess.run([sys.executable, "-c", _COLD.format(preset=args.preset, extra=extra)], cwd=root,
                               capture_output=True, text=True, check=True)
            t, mb = json.loads(r.stdout.strip().splitlines()[-1])
            cold.append(t)
            peak.append(mb)
        warm = []
        for _ in range(args.repeats):
            t = time.perf_counter()
            corpus = SyntheticTalker(preset=args.preset, **extra).generate()
            warm.append(time.perf_counter() - t)
        print(f"\n== {label}, preset {args.preset!r}: {corpus.n_frames} frames, {corpus.n_points} points")
        print(f"generation cold (fresh process, imports included): min {min(cold):.1f} s, median "
              f"{statistics.median(cold):.1f} s; warm: min {min(warm):.1f} s, median {statistics.median(warm):.1f} s; "
              f"peak RSS {max(peak):.0f} MB ({args.repeats} repeats)")
        if args.generation_only:
            continue
        if PRESETS[args.preset]["speakers"] == 1:  # what the controls alone make of the surface
            lip = LipModel(PRESETS[args.preset]["resolution"], speaker_anatomy(extra.get("seed", 0), 0))
            C = np.column_stack([corpus.latent[k] for k in CONTROL_NAMES])
            for line in format_articulation(articulation_report(lip, C)):
                print(line)
        t = time.perf_counter()
        m = Manifold().fit(corpus)
        print(f"Manifold().fit {time.perf_counter() - t:.1f} s")
        for line in format_realism(talker_realism(m)):
            print(line)


if __name__ == "__main__":
    main()

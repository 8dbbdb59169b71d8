"""How real the synthetic talker is to the method: generation time, X scree, Y1-3 variance,
and the tangent classes' agreement with the exact ground truth next to the trivial
Delta F^x_1 rule (engine.talker.report), for the default and the held-out talker; and the
scree of four articulograph sensors (upper and lower lip, left corner, jaw) on the talker
(engine.talker.virtual_sensors) beside the same sensors of real speakers (the Haskins IEEE pair,
when --haskins-dir holds it).

Run: .venv/bin/python tools/talker_realism.py [--preset default] [--repeats 3] [--skip-heldout]
     [--generation-only] [--tissue] [--kinematics calibrated] [--haskins-dir DIR]
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
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _common, beside the benchmarks

from _common import blas_kernel  # noqa: E402

_COLD = ("import time, json, resource; t=time.perf_counter(); from engine.talker.synthetic import SyntheticTalker; "
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
    ap.add_argument("--kinematics", default="classic", choices=("classic", "calibrated"),
                    help="SyntheticTalker(kinematics=...) for both talkers")
    ap.add_argument("--haskins-dir", default=str(_HASKINS), help="real EMA recordings (*.mat) to compare the "
                    "talker's sensors with (default: %(default)s; skipped when absent)")
    ap.add_argument("--mocha-dir", default=str(_MOCHA), help="a real 2-D articulograph recording (*.ema) for the "
                    "held-out check of the sensors' movement (default: %(default)s; skipped when absent)")
    args = ap.parse_args(argv)
    import os

    from engine.manifold.model import Manifold
    from engine.talker.lipmodel import CONTROL_NAMES, LipModel
    from engine.talker.report import articulation_report, format_articulation, format_realism, talker_realism
    from engine.talker.synthetic import HELD_OUT_TALKER, PRESETS, SyntheticTalker, speaker_anatomy
    from engine.talker.virtual_sensors import SENSOR_ROLES, sensor_motion, sensor_scree, virtual_sensors

    print(f"BLAS: {blas_kernel()}")
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f}")
    root = Path(__file__).resolve().parent.parent
    talkers = [("default talker", {})] + ([] if args.skip_heldout else [("held-out talker", HELD_OUT_TALKER)])
    if args.tissue:
        talkers = [(f"{label} with tissue variation", {**extra, "tissue": True}) for label, extra in talkers]
    if args.kinematics != "classic":
        talkers = [(f"{label}, {args.kinematics} kinematics", {**extra, "kinematics": args.kinematics})
                   for label, extra in talkers]
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
            lip = LipModel(PRESETS[args.preset]["resolution"], speaker_anatomy(extra.get("seed", 0), 0),
                           kinematics=args.kinematics)
            C = np.column_stack([corpus.latent[k] for k in CONTROL_NAMES])
            for line in format_articulation(articulation_report(lip, C)):
                print(line)
        sensors = virtual_sensors(LipModel(PRESETS[args.preset]["resolution"]))
        pts = [sensors[k] for k in SENSOR_ROLES]
        print(_sensor_line(f"talker's sensors {'/'.join(SENSOR_ROLES)}", sensor_scree(corpus.frames, pts),
                           sensor_motion(corpus.frames, pts), SENSOR_ROLES))
        # the midsagittal view of a 2-D articulograph (MOCHA): UL, LL and the jaw, vertical and depth
        mid = np.asarray(corpus.frames).reshape(corpus.n_frames, -1, 3)[:, [pts[0], pts[1], pts[3]], 1:]
        print(_motion_line("talker's sensors, midsagittal (2-D)", sensor_motion(mid.reshape(len(mid), -1), [0, 1, 2],
                                                                               dims=2), ("UL", "LL", "JAW")))
        t = time.perf_counter()
        m = Manifold().fit(corpus)
        print(f"Manifold().fit {time.perf_counter() - t:.1f} s")
        for line in format_realism(talker_realism(m)):
            print(line)
    _real_sensors(Path(args.haskins_dir), Path(args.mocha_dir), SENSOR_ROLES)


_DATA = Path(__file__).resolve().parent.parent.parent / "shared" / "data"
_HASKINS, _MOCHA = _DATA / "haskins-ieee", _DATA / "mocha-fsew0"


def _motion_line(label, motion, roles):
    """Each sensor's RMS movement (mm) and, in brackets, its ratio to the lower lip's."""
    ll = motion[list(roles).index("LL")]
    return (f"{label}{': ' if label else ''}RMS movement (mm, / LL's) "
            + ", ".join(f"{k} {v:.2f} ({v / ll:.2f})" for k, v in zip(roles, motion)))


def _sensor_line(label, r, motion, roles):
    return (f"{label}: components for 80/90/95 % of their variance: {', '.join(map(str, r['components']))}; "
            "scree " + " ".join(f"{100 * v:.1f}" for v in r["scree"][:5]) + "\n  " + _motion_line("", motion, roles))


def _real_sensors(haskins, mocha, roles):
    """The same four sensors of each real 3-D recording (Haskins), and UL, LL and the lower
    incisor of the midsagittal MOCHA recording, which the calibrated kinematics were not set on."""
    from engine.io.dispatch import read_corpus
    from engine.talker.virtual_sensors import sensor_motion, sensor_scree

    files = sorted(haskins.glob("*.mat")) if haskins.is_dir() else []
    print("\n== real speakers' sensors (the same roles)" if files else f"\nreal sensors: nothing in {haskins}")
    for f in files:
        c = read_corpus(str(f))
        names = list(c.point_names or ())
        if not all(k in names for k in roles):
            print(f"{f.name}: lacks one of {roles} (has {names}); skipped")
            continue
        pts = [names.index(k) for k in roles]
        print(_sensor_line(f"{f.name} ({c.n_frames} frames at {c.rate:g} Hz)", sensor_scree(c.frames, pts),
                           sensor_motion(c.frames, pts), roles))
    for f in sorted(mocha.glob("*.ema")) if mocha.is_dir() else []:
        c = read_corpus(str(f))
        names = list(c.point_names or ())
        if c.dims != 2 or not all(k in names for k in ("UL", "LL", "LI")):
            continue
        print(_motion_line(f"{f.name} (2-D, lower incisor as JAW; held out)",
                           sensor_motion(c.frames, [names.index(k) for k in ("UL", "LL", "LI")], dims=2),
                           ("UL", "LL", "JAW")))


if __name__ == "__main__":
    main()

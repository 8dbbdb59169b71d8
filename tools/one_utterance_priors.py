"""The `states` protocol when training holds one utterance: which interpolation the manifold
method should fall back on without a validation split (DECISIONS G14).

With fewer than three training utterances there is no validation split, and the manifold
method is its prior blend. This script measures the candidates for that prior in the
regime itself, on development data only: draws of one training utterance and a dozen test
utterances from the default synthetic talker (same speaker) and from the four-speaker
talker (training and test speakers differ, speaker means removed, as for the Haskins
pair). Beside the methods of the `states` protocol it scores the even average of the
state-velocity Hermite spline and linear interpolation (`sv-hermite+linear`), a candidate
that was measured and rejected. With ``--haskins-dir`` holding the Haskins pair it then
prints the same candidates on each cross-speaker direction, with the comparisons over the
sentence's gaps.

Run: .venv/bin/python tools/one_utterance_priors.py [--draws 8] [--tests 20] [--seed 1]
     [--haskins-dir DIR]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # the engine, from a checkout
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _common, beside the benchmarks

from _common import blas_kernel  # noqa: E402

AVERAGE = "sv-hermite+linear"
_HASKINS = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "haskins-ieee"


def _with_average(trajectories, *, as_manifold=False):
    """``trajectories`` with the even average of sv-hermite and linear added to the states
    protocol (``as_manifold``: in place of the manifold method, for the paired comparisons)."""
    def wrapped(*args, **kw):
        out, missed = trajectories(*args, **kw)
        s = out["states"]
        s["manifold" if as_manifold else AVERAGE] = 0.5 * (s["sv-hermite"] + s["linear"])
        return out, missed
    return wrapped


def _draws(corpus, pairs, n_tests, rng):
    """Per method the pooled states-protocol RMSE X of each draw (one training utterance each)."""
    from engine.evaluation.protocols import evaluate_protocols

    per = {}
    for train_pool, test_pool in pairs:
        train = train_pool[rng.integers(len(train_pool))]
        test = [t for t in rng.permutation(test_pool).tolist() if t != train][:n_tests]
        r = evaluate_protocols(corpus.subset(sorted([train] + test)), random_state=0, test_ids=test,
                               inverse_table=False, phones=False)
        for row in r.rows:
            if row["protocol"] == "states":
                per.setdefault(row["method"], []).append(row["rmse_x"])
    return per


def _print(title, per):
    ref = {m: np.asarray(per[m]) for m in ("sv-hermite", "linear")}
    print(f"\n{title} ({len(per['linear'])} draws; RMSE X, mean over draws; draws where the method erred less)")
    for m, v in sorted(per.items(), key=lambda kv: np.mean(kv[1])):
        v = np.asarray(v)
        print(f"  {m:18s} {v.mean():8.3f}   < sv-hermite {int((v < ref['sv-hermite']).sum()):2d}   "
              f"< linear {int((v < ref['linear']).sum()):2d}")


def _haskins(folder, plain):
    import engine.evaluation.protocols as protocols
    from app.cli.evaluate import haskins_speaker, name_haskins_speakers, normalise_per_speaker
    from engine.io import read_corpus

    mats = sorted(Path(folder).glob("*.mat"))
    if len(mats) < 2:
        print(f"\nHaskins: no pair of *.mat in {folder}; skipped")
        return
    raw = name_haskins_speakers(read_corpus([str(p) for p in mats]))
    norm = normalise_per_speaker(raw)
    for u in raw.utterances:
        protocols.trajectories = _with_average(plain)
        r = protocols.evaluate_protocols(norm, random_state=0, test_ids=[u.id], inverse_table=False)
        rows = {x["method"]: x["rmse_x"] for x in r.rows if x["protocol"] == "states"}
        print(f"\nHaskins, test {haskins_speaker(u)} (normalised), states: "
              + ", ".join(f"{m} {v:.4g}" for m, v in sorted(rows.items(), key=lambda kv: kv[1])))
        protocols.trajectories = _with_average(plain, as_manifold=True)  # the average in the manifold's column
        r = protocols.evaluate_protocols(norm, random_state=0, test_ids=[u.id], inverse_table=False)
        for c in r.comparisons:
            if c["protocol"] == "states" and c["measure"] == "rmse_x" and c["method"] in ("sv-hermite", "linear"):
                print(f"  {c['method']} - {AVERAGE}: {c['mean_diff']:+.4f} [{c['ci_low']:+.4f}, {c['ci_high']:+.4f}] "
                      f"over {c['n']} gaps; the average erred less on {c['wins']}; p {c['p_sign']:.2g} sign / "
                      f"{c['p_wilcoxon']:.2g} signed-rank")
    protocols.trajectories = plain


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=8, help="training utterances drawn per corpus")
    ap.add_argument("--tests", type=int, default=20, help="test utterances per draw")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--haskins-dir", default=str(_HASKINS), help="the Haskins pair (skipped when absent)")
    args = ap.parse_args(argv)
    import engine.evaluation.protocols as protocols
    from engine.recordings.registration import normalise_speakers
    from engine.talker.synthetic import load_synthetic

    plain = protocols.trajectories
    protocols.trajectories = _with_average(plain)
    print(f"BLAS: {blas_kernel()}")
    rng = np.random.default_rng(args.seed)
    talker = load_synthetic(preset="default")
    ids = [u.id for u in talker.utterances]
    _print("default talker, one training utterance", _draws(talker, [(ids, ids)] * args.draws, args.tests, rng))
    multi = normalise_speakers(load_synthetic(preset="multi"), mode="mean")
    spk = {}
    for u in multi.utterances:
        spk.setdefault(u.speaker, []).append(u.id)
    names = sorted(spk)
    pairs = [tuple(spk[names[i]] for i in rng.choice(len(names), size=2, replace=False)) for _ in range(args.draws)]
    _print("four-speaker talker, training and test speakers differ", _draws(multi, pairs, args.tests, rng))
    _haskins(args.haskins_dir, plain)


if __name__ == "__main__":
    main()

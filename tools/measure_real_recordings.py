"""Real-recording faults and their fixes, measured: opening agreement, connectivity, build time.

Two inputs:

* the Haskins IEEE pair (``--haskins DIR``, default ``../shared/data/haskins-ieee`` beside
  the project when present): two speakers, one sentence each, 100 Hz;
* a generated 3-speaker articulograph corpus (:mod:`engine.talker.multispeaker`): 7 sensors x 6
  values at 250 Hz, speaker origins 100 mm apart, offsets between utterances, head
  motion, tongue sensors; with and without head reference sensors.

For each condition it prints the agreement of the opening class with the lip aperture
increasing (% of moving frames), the state graph's strongly connected components
(count, share of states in the largest), the split warning's cause if any, and the
build's wall time and peak traced memory, plus the BLAS kernel (threadpoolctl).

    .venv/bin/python tools/measure_real_recordings.py [--utterances 6] [--seed 0]
"""
from __future__ import annotations

import argparse
import time
import tracemalloc
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from engine.io import concat, read_corpus, resample
from engine.io.readers.matrix import corpus_from_matrix
from engine.manifold.class_agreement import class_agreement
from engine.manifold.model import Manifold
from engine.recordings.corpus import CorpusWarning, Utterance
from engine.recordings.kinematics import lip_aperture
from engine.recordings.layouts import BUILTIN, read_layout
from engine.recordings.registration import register
from engine.talker.multispeaker import generate_recordings, layout_text

HASKINS = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "haskins-ieee"


def _blas():
    try:
        from threadpoolctl import threadpool_info

        return ", ".join(f"{i.get('internal_api')} {i.get('architecture', '')} x{i.get('num_threads')}"
                         for i in threadpool_info())
    except ImportError:
        return "threadpoolctl not installed"


def measure(label, corpus, *, roles_for_score, use_aperture=True, speaker_norm="auto", n_states=None):
    c = corpus if use_aperture else replace(corpus, point_roles=None)
    tracemalloc.start()
    t = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", CorpusWarning)
        m = Manifold(n_states=n_states, speaker_normalisation=speaker_norm).fit(c)
    wall = time.perf_counter() - t
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    ap = lip_aperture(replace(m.corpus_, point_roles=roles_for_score))
    agree = class_agreement(m.tangent_.opening_, m.tangent_.accelerating_, ap, m.corpus_.bounds).opening
    scc = np.bincount(m.states_.scc_labels_)
    split = next((str(w.message).split(" along ")[1].split(":")[0] for w in caught if " along " in str(w.message)),
                 "-")
    print(f"  {label:64s} {100 * agree:5.1f}%  {len(scc):3d} SCC, largest {100 * scc.max() / scc.sum():5.1f}%  "
          f"split along: {split:10s}  {m.corpus_.rate:5.0f} Hz  {wall:5.2f} s  {peak:6.1f} MiB")
    return agree


def generated(n_utt, seed, reference):
    recs = generate_recordings(n_speakers=3, n_utterances=n_utt, reference=reference, seed=seed)
    if reference:
        import tempfile

        with tempfile.TemporaryDirectory() as d:
            f = Path(d) / "ref.layout"
            f.write_text(layout_text(reference=True))
            lay = read_layout(f)
    else:
        lay = BUILTIN["ema7x6"]
    out = {}
    for points in (None, "all", "lips"):
        parts = []
        for r in recs:
            c = corpus_from_matrix(f"{r.id}.csv", r.matrix, lay, rate=r.rate, points=points)
            parts.append(replace(c, utterances=[Utterance(r.id, 0, c.n_frames, speaker=r.speaker)], name=r.id))
        out[{None: "default", "all": "all", "lips": "lips"}[points]] = concat(parts, name="generated")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--utterances", type=int, default=6, help="generated utterances per speaker (default 6)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--haskins", type=Path, default=HASKINS)
    args = ap.parse_args(argv)
    print(f"BLAS: {_blas()}")
    print(f"  {'condition':64s} agree   connectivity                                    rate   build  peak")
    files = sorted(args.haskins.glob("*.mat")) if args.haskins.is_dir() else []
    if files:
        raw = read_corpus([str(f) for f in files])
        roles = raw.point_roles
        print(f"Haskins IEEE pair ({', '.join(f.stem for f in files)}), sensors {', '.join(raw.point_names)}:")
        measure("100 Hz, no registration, opening = F^x_1 (before issue 12)", raw, roles_for_score=roles,
                use_aperture=False, speaker_norm="none", n_states=24)
        measure("100 Hz, no registration, opening = aperture", raw, roles_for_score=roles, speaker_norm="none",
                n_states=24)
        measure("60 Hz, no registration, opening = F^x_1", resample(raw, 60), roles_for_score=roles,
                use_aperture=False, speaker_norm="none", n_states=24)
        reg = resample(register(raw, method="utterance"), 60)
        measure("60 Hz, utterance centring, aperture (lipspace import default)", reg, roles_for_score=roles,
                n_states=24)
        spk = replace(reg, utterances=[replace(u, speaker=u.id.split("_")[0]) for u in reg.utterances])
        measure("  + speakers F01/M01 (import --speaker-from prefix)", spk, roles_for_score=roles, n_states=24)
    else:
        print(f"Haskins pair not found in {args.haskins}; skipped")
    for reference in (False, True):
        g = generated(args.utterances, args.seed, reference)
        lip_roles = g["lips"].point_roles
        print(f"generated: 3 speakers x {args.utterances} utterances, 250 Hz, "
              f"{'with' if reference else 'without'} head reference sensors:")
        allp = g["all"]
        no_spk = replace(allp, utterances=[replace(u, speaker="") for u in allp.utterances])
        measure("all sensors (tongue too), no registration, F^x_1 (before)", no_spk,
                roles_for_score=allp.point_roles, use_aperture=False, speaker_norm="none")
        measure("all sensors, no registration, aperture", no_spk, roles_for_score=allp.point_roles,
                speaker_norm="none")
        if reference:  # import default with a layout naming the head sensors: lips + references, rigid
            r = register(g["default"], method="rigid")
            measure("lips, rigid registration, speaker norm, aperture, 250 Hz", r, roles_for_score=lip_roles)
            measure("lips, rigid registration, speaker norm, aperture, 60 Hz (default)", resample(r, 60),
                    roles_for_score=lip_roles)
        r = register(g["lips"], method="utterance")  # lip sensors only: head motion within utterances stays
        scored = lip_roles
        measure("lips, utterance centring, no speaker norm, aperture, 60 Hz", resample(r, 60),
                roles_for_score=scored, speaker_norm="none")
        measure("lips, utterance centring, speaker norm, aperture, 250 Hz", r, roles_for_score=scored)
        measure("lips, utterance centring, speaker norm, aperture, 60 Hz (default)", resample(r, 60),
                roles_for_score=scored)


if __name__ == "__main__":
    main()

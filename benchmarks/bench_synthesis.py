"""Benchmark: synthesise a 3-second utterance and map its frames back to the mesh; print wall time and peak memory.

Usage: python benchmarks/bench_synthesis.py [--preset paper|default|small] [--manifold FILE] [--seconds 3]
                                            [--repeat 5] [--cache-dir DIR]

Target (issue 4): on the paper-scale preset, synthesis of a 3-s utterance plus the
inverse map of its frames well under 100 ms (after the one-time set-up: fitting the
manifold, building the Delaunay inverse map, preparing the synthesisers, which are
timed separately).
"""
from __future__ import annotations

import argparse

import numpy as np
from _common import first_phones
from _harness import Harness


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--manifold", default=None, help="a saved manifold instead of fitting the preset")
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--cache-dir", default=None)
    Harness.add_arguments(ap)
    args = ap.parse_args()
    bench = Harness("bench_synthesis", args)

    def timed(name, fn, *, repeat=0, headline=False):
        """The first call (cold in this process for the set-up steps), then ``repeat`` warm calls:
        returns the output and the warm median (the single time when there are no repeats)."""
        out, m = bench.measure(name, fn, repeat=repeat, cold=None if repeat else True, headline=headline)
        return out, m.median

    from engine.manifold.model import Manifold
    from engine.phonetics.targets import targets_from_phones, targets_from_points
    from engine.synthesis.methods import make_synthesizer
    from engine.talker.synthetic import load_synthetic

    print("one-time set-up")
    if args.manifold:
        m, _ = timed("load manifold", lambda: Manifold.load(args.manifold))
    else:
        corpus, _ = timed(f"corpus '{args.preset}' (cache/generate)",
                          lambda: load_synthetic(preset=args.preset, cache_dir=args.cache_dir))
        m, _ = timed("fit manifold", lambda: Manifold().fit(corpus))
    c = m.corpus_
    K = m.states_.centroids_.shape[0]
    print(f"corpus {c.n_frames} frames x {c.frames.shape[1]} coordinates; X {m.Fx_.shape[1]} components; "
          f"K = {K} states, {m.states_.counts_.nnz} observed transitions")
    inv, _ = timed("inverse map: Delaunay + simplex transforms",
                   lambda: (m.inverse_map, m.inverse_map.transform(m.Fy_[:1]))[0])
    print(f"  {inv.simplices_.shape[0]} tetrahedra over {inv.points_.shape[0]} points "
          f"({inv.n_duplicates_} duplicates, {inv.n_dropped_} left out by Qhull)")
    synths = {}
    for meth in ("viterbi", "linear", "cubic", "unitselection"):
        kw = {"strict": False} if meth == "viterbi" else {}  # undershoot unreachable targets, as the CLI does
        synths[meth], _ = timed(f"prepare {meth}", lambda meth=meth, kw=kw: make_synthesizer(meth, m, **kw))
    synths["viterbi"].synthesize(targets_from_phones(m, "sil 0.1 m 0.1"))  # builds the phone table once

    phones, u = first_phones(c, args.seconds)
    tg_phones = targets_from_phones(m, phones)
    # oracle-style targets: the states of the corpus frames at the same mid-points
    frames = tg_phones.frames
    st = m.states_.labels_[u.start + frames]
    tg_states = targets_from_points(m, list(zip(frames.tolist(), st.tolist())), n_frames=tg_phones.n_frames)
    n = tg_phones.n_frames
    print(f"\nsynthesis of {n / c.rate:.2f} s = {n} frames, {len(tg_phones.targets)} phone targets "
          f"(3-second utterance)")
    results = {}
    tr, t_states = timed("viterbi (the paper's path), state targets",
                         lambda: synths["viterbi"].synthesize(tg_states), repeat=args.repeat)
    tr_p, t_phones = timed("viterbi, phone targets (lattice, M=8)",
                             lambda: synths["viterbi"].synthesize(tg_phones), repeat=args.repeat, headline=True)
    for meth in ("linear", "cubic", "unitselection"):
        _, results[meth] = timed(meth, lambda meth=meth: synths[meth].synthesize(tg_phones), repeat=args.repeat)
    _, t_inv = timed("inverse map of the frames (Y -> X)", lambda: inv.transform(tr.Fy), repeat=args.repeat)
    _, t_mesh = timed("frames F = mean + X X^T", lambda: tr.frames(m), repeat=args.repeat)

    def full():
        t = synths["viterbi"].synthesize(tg_phones)
        return t.frames(m)

    _, t_full = timed("TOTAL: phones -> state path -> X -> frames", full, repeat=args.repeat, headline=True)
    print(f"\nmanifold synthesis incl. inverse map: {1000 * t_states:.1f} ms (state targets), "
          f"{1000 * t_phones:.1f} ms (phone targets); with mesh frames {1000 * t_full:.1f} ms "
          f"[target: well under 100 ms]; inverse map alone {1000 * t_inv:.2f} ms, mesh {1000 * t_mesh:.2f} ms")
    print(f"missed targets: {len(tr.warnings)} (state targets), {len(tr_p.warnings)} (phone targets)")
    print(f"(numpy {np.__version__})")
    bench.finish()


if __name__ == "__main__":
    main()

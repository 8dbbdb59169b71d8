"""Benchmark: what the first synthesis with the default method ``best`` costs on a corpus.

Usage: python benchmarks/bench_method_choice.py [--preset small|default] [--cache-dir DIR]

``best`` resolves through :func:`engine.synthesis.method_choice.choose_methods`: the whole validation
of :func:`engine.evaluation.protocols.select_settings` on the loaded manifold, once per corpus, then
a JSON file in the cache. Printed: the manifold fit (for scale), the validation cold (no
cached choice; wall time, peak RSS) and warm (the cached JSON read back), the fitting of
the manifold method's state model for synthesis, and one synthesis of a 3-second phone
string by the chosen method. The BLAS kernel in use is printed too.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import blas_kernel, first_phones, peak_rss_mb  # noqa: E402


def timed(label, fn):
    t = time.perf_counter()
    out = fn()
    print(f"{label:48s} {time.perf_counter() - t:8.1f} s   peak RSS {peak_rss_mb():6.0f} MiB", flush=True)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="default", choices=("small", "default"))
    ap.add_argument("--cache-dir", default=None, help="synthetic talker cache")
    args = ap.parse_args()

    from engine.manifold.model import Manifold
    from engine.phonetics.targets import targets_from_phones
    from engine.synthesis.method_choice import best_method, choose_methods, describe, target_protocol
    from engine.synthesis.methods import make_synthesizer
    from engine.talker.synthetic import load_synthetic

    print(f"BLAS: {blas_kernel()}")
    corpus = timed(f"corpus '{args.preset}'", lambda: load_synthetic(preset=args.preset, cache_dir=args.cache_dir))
    m = timed("fit manifold", lambda: Manifold().fit(corpus))
    with tempfile.TemporaryDirectory() as tmp:
        choice = timed("validation, cold (no cached choice)", lambda: choose_methods(m, cache_dir=tmp))
        timed("validation, warm (cached JSON)", lambda: choose_methods(m, cache_dir=tmp))
    phones, _ = first_phones(m.corpus_, 3.0)
    tg = targets_from_phones(m, phones)
    method = best_method(choice, target_protocol(tg))
    print(describe(choice, target_protocol(tg), method))
    syn = timed(f"fit '{method}' for synthesis", lambda: make_synthesizer(method, m, **(
        {"choice": choice} if method in ("manifold", "sv-hermite") else {})))
    timed(f"synthesise {tg.n_frames} frames with '{method}'", lambda: syn.synthesize(tg))
    syn = timed("fit 'manifold' for synthesis (state model)", lambda: make_synthesizer("manifold", m, choice=choice))
    timed(f"synthesise {tg.n_frames} frames with 'manifold'", lambda: syn.synthesize(tg))


if __name__ == "__main__":
    main()

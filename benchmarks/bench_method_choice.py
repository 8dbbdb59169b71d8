"""Benchmark: what the first synthesis with the default method ``best`` costs on a corpus.

Usage: python benchmarks/bench_method_choice.py [--preset small|default] [--cache-dir DIR]

``best`` resolves through :func:`engine.synthesis.method_choice.choose_methods`: the whole validation
of :func:`engine.evaluation.protocols.select_settings` on the loaded manifold, once per corpus, then
a JSON file in the cache. Printed: the manifold fit (for scale), the validation cold (no
cached choice; wall time, peak RSS) and warm (the cached JSON read back), the fitting of
the manifold method's state model for synthesis, and one synthesis of a 3-second phone
string by the chosen method. The BLAS kernel in use is printed too.

``--cold`` measures, each in a fresh process, what the explorer's first synthesis costs:
``choose_methods(use_cache=False)`` (wall time, peak RSS) and the synthesiser's full state
model fit (``make_synthesizer("manifold", m, choice=...)``), on every ``--manifold``
(``talker``: the synthetic talker of ``--preset``, fitted first, untimed; or a saved
manifold, read with ``Manifold.load``). ``--vs-tree DIR`` runs the same child on the
engine of another checkout too, alternating which goes first; ``--repeats`` gives min and
median; ``--timeout`` ends a child that runs longer (reported, not fatal). The load
average before and after and the note of the choice are printed.

Usage: python benchmarks/bench_method_choice.py --cold [--manifold FILE|talker ...]
       [--vs-tree DIR] [--repeats 1] [--timeout 1800]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import blas_kernel, first_phones, peak_rss_mb, run_child_json  # noqa: E402


def timed(label, fn):
    t = time.perf_counter()
    out = fn()
    print(f"{label:48s} {time.perf_counter() - t:8.1f} s   peak RSS {peak_rss_mb():6.0f} MiB", flush=True)
    return out


def child(spec, preset, cache_dir):
    """One cold measurement in this process: the choice, then the synthesiser's state model fit."""
    from engine.manifold.model import Manifold
    from engine.synthesis.method_choice import choose_methods
    from engine.synthesis.methods import make_synthesizer

    t = time.perf_counter()
    if spec == "talker":
        from engine.talker.synthetic import load_synthetic

        m = Manifold().fit(load_synthetic(preset=preset, cache_dir=cache_dir))
    else:
        m = Manifold.load(spec)
    t_load, rss_load = time.perf_counter() - t, peak_rss_mb()
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        choice = choose_methods(m, cache_dir=tmp, use_cache=False)
        t_choice, rss_choice = time.perf_counter() - t, peak_rss_mb()
    t = time.perf_counter()
    syn = make_synthesizer("manifold", m, choice=choice)
    t_fit, rss_fit = time.perf_counter() - t, peak_rss_mb()
    return {"frames": int(m.Fy_.shape[0]), "utterances": len(m.corpus_.utterances), "load_s": t_load,
            "load_rss": rss_load, "choice_s": t_choice, "choice_rss": rss_choice, "fit_s": t_fit, "fit_rss": rss_fit,
            "K": int(syn.model_.n_states_), "state_dims": int(choice["state_dims"]),
            "frames_per_state": choice.get("frames_per_state"), "best": choice.get("best"), "note": choice.get("note"),
            "blas": blas_kernel()}


def cold(args):
    here = str(Path(__file__).resolve().parents[1])
    trees = [("this", here)] + ([("vs-tree", str(Path(args.vs_tree).resolve()))] if args.vs_tree else [])
    print(f"BLAS (parent): {blas_kernel()}\nload average before: "
          f"{'/'.join(f'{x:.1f}' for x in os.getloadavg())}; {os.cpu_count()} cores", flush=True)
    runs = {}
    for spec in args.manifold:
        for r in range(args.repeats):
            for name, root in (trees if r % 2 == 0 else trees[::-1]):
                cmd = [sys.executable, str(Path(__file__).resolve()), "--child", "--root", root, "--manifold", spec,
                       "--preset", args.preset, *(["--cache-dir", args.cache_dir] if args.cache_dir else [])]
                env = {**os.environ, "PYTHONPATH": root}
                t = time.perf_counter()
                try:
                    out = run_child_json(cmd, env=env, cwd=root, timeout=args.timeout)
                except subprocess.TimeoutExpired:
                    out = {"timeout": args.timeout}
                    print(f"{spec} [{name}] round {r}: did not finish in {args.timeout:.0f} s "
                          f"({time.perf_counter() - t:.0f} s wall)", flush=True)
                else:
                    print(f"{spec} [{name}] round {r}: {out['frames']} frames, {out['utterances']} utterances; "
                          f"load {out['load_s']:.1f} s; choose_methods {out['choice_s']:.1f} s (peak RSS "
                          f"{out['choice_rss']:.0f} MiB); state model fit {out['fit_s']:.1f} s, K {out['K']} (peak RSS "
                          f"{out['fit_rss']:.0f} MiB); load average {os.getloadavg()[0]:.1f}\n   note: {out['note']}\n"
                          f"   BLAS: {out['blas']}", flush=True)
                runs.setdefault((spec, name), []).append(out)
    print("\nsummary (min / median over repeats)")
    for (spec, name), outs in runs.items():
        ok = [o for o in outs if "timeout" not in o]
        if not ok:
            print(f"  {spec} [{name}]: no run finished within {args.timeout:.0f} s")
            continue
        line = "; ".join(f"{k} {min(o[k] for o in ok):.1f} / {statistics.median(o[k] for o in ok):.1f} s"
                         for k in ("choice_s", "fit_s"))
        print(f"  {spec} [{name}]: {line}; peak RSS {max(o['fit_rss'] for o in ok):.0f} MiB; "
              f"{len(ok)} of {len(outs)} finished")
    print(f"load average after: {'/'.join(f'{x:.1f}' for x in os.getloadavg())}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="default", choices=("small", "default"))
    ap.add_argument("--cache-dir", default=None, help="synthetic talker cache")
    ap.add_argument("--cold", action="store_true", help="fresh-process cold figures (see the module docstring)")
    ap.add_argument("--manifold", nargs="+", default=["talker"], help="'talker' or saved manifold files (--cold)")
    ap.add_argument("--vs-tree", default=None, metavar="DIR", help="also run the engine of this checkout (--cold)")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds before a child is ended (--cold)")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--root", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.repeats < 1:
        ap.error(f"--repeats must be >= 1, got {args.repeats}")
    if args.child:
        if args.root:
            sys.path.insert(0, args.root)
        print(json.dumps(child(args.manifold[0], args.preset, args.cache_dir)))
        return
    if args.cold:
        cold(args)
        return

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

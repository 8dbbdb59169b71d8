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

``--first`` measures the first synthesis as a user meets it: each in a fresh process, the
manifold is loaded as the window loads it (``talker``: :func:`app.files.source_loading.load_source`,
the shipped or cached talker; a file: ``Manifold.load``; timed apart), then one synthesis with
``best`` through the window's own function (:func:`app.models.trajectories.synthesize_targets`:
the choice -- stored in the file, cached, or measured -- the synthesiser's fit and the
synthesis) from targets of each protocol: ``states`` (five states of the graph, 0.2 s
apart), ``phones`` (the text "bob meets mum") and ``oracle`` (the longest utterance's own
phone mid-points). Printed per run: load and first-synthesis seconds, the method, whether
the file held the choice, peak RSS; then min / median per manifold and protocol.

Usage: python benchmarks/bench_method_choice.py --first [--manifold FILE|talker ...] [--repeats 3]
       [--protocols states phones oracle]
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
import numpy as np  # noqa: E402
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


def child_first(spec, preset, protocol):
    """One fresh process: load ``spec`` as the window does, then the first synthesis of ``protocol`` targets."""
    from engine.manifold.model import Manifold

    t = time.perf_counter()
    if spec == "talker":
        from app.files.source_loading import load_source

        m = load_source(None, preset, prepare_views=False)[0]
    else:
        m = Manifold.load(spec)
    t_load = time.perf_counter() - t
    from app.models.trajectories import synthesize_targets
    from engine.phonetics import targets as T
    from engine.synthesis.method_choice import stored_choice

    if protocol == "states":
        K = m.states_.centroids_.shape[0]
        tg = T.targets_from_points(m, [(12 * k, int(s)) for k, s in enumerate(np.linspace(0, K - 1, 5).astype(int))],
                                   n_frames=4 * 12 + 1)
    elif protocol == "phones":
        tg = T.targets_from_text(m, "bob meets mum")
    else:
        u = max(m.corpus_.utterances, key=lambda x: x.n_frames if x.phones else 0)
        tg = T.targets_from_utterance(m, u.id, on_collision="merge")
    t = time.perf_counter()
    data, _traj = synthesize_targets(m, tg, "best")
    t_first = time.perf_counter() - t
    return {"frames": int(m.Fy_.shape[0]), "load_s": t_load, "first_s": t_first, "method": data.extra["method"],
            "stored": stored_choice(m) is not None, "n_frames": int(tg.n_frames), "rss": peak_rss_mb(),
            "blas": blas_kernel(), "load": os.getloadavg()[0]}


def first(args):
    from _harness import Harness

    bench = Harness("bench_method_choice", args, quiet=True)  # the record of the figures printed below
    print(f"BLAS (parent): {blas_kernel()}\nload average before: "
          f"{'/'.join(f'{x:.1f}' for x in os.getloadavg())}; {os.cpu_count()} cores", flush=True)
    here = str(Path(__file__).resolve().parents[1])
    runs = {}
    for r in range(args.repeats):
        for spec in args.manifold:
            for protocol in args.protocols:
                cmd = [sys.executable, str(Path(__file__).resolve()), "--child-first", protocol, "--manifold", spec,
                       "--preset", args.preset]
                try:
                    out = run_child_json(cmd, cwd=here, timeout=args.timeout)
                except subprocess.TimeoutExpired:
                    print(f"{spec} {protocol} round {r}: did not finish in {args.timeout:.0f} s", flush=True)
                    continue
                runs.setdefault((spec, protocol), []).append(out)
                print(f"{spec} {protocol} round {r}: {out['frames']} frames; load {out['load_s']:.2f} s; "
                      f"first synthesis {out['first_s']:.2f} s ({out['method']}, {out['n_frames']} frames; "
                      f"choice stored in the file: "
                      f"{out['stored']}); peak RSS {out['rss']:.0f} MiB; load average {out['load']:.1f}", flush=True)
    print("\nsummary: first synthesis with 'best' (min / median over fresh processes)")
    for (spec, protocol), outs in runs.items():
        v = [o["first_s"] for o in outs]
        ld = [o["load_s"] for o in outs]
        print(f"  {spec} {protocol}: {min(v):.2f} / {statistics.median(v):.2f} s ({outs[0]['method']}); load "
              f"{min(ld):.2f} / {statistics.median(ld):.2f} s; n={len(v)}")
        label = f"{Path(spec).name if spec != 'talker' else 'talker'}, {outs[0]['frames']} frames, {protocol}"
        bench.figure(f"first synthesis with 'best' [{label}]", v, cold=True, headline=True,
                     peak_rss_mib=max(o["rss"] for o in outs), show=False, method=outs[0]["method"])
        bench.figure(f"manifold load [{label}]", ld, cold=True, show=False)
    print(f"BLAS (child): {next(iter(runs.values()))[0]['blas'] if runs else '-'}")
    print(f"load average after: {'/'.join(f'{x:.1f}' for x in os.getloadavg())}")
    bench.finish()


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
    ap.add_argument("--first", action="store_true", help="the first synthesis with 'best', fresh processes "
                                                          "(see the module docstring)")
    ap.add_argument("--protocols", nargs="+", default=["states", "phones", "oracle"],
                    choices=("states", "phones", "oracle"), help="targets of the first synthesis (--first)")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--child-first", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--root", default=None, help=argparse.SUPPRESS)
    from _harness import Harness

    Harness.add_arguments(ap)
    args = ap.parse_args()
    if args.repeats < 1:
        ap.error(f"--repeats must be >= 1, got {args.repeats}")
    if args.child_first:
        import warnings

        warnings.simplefilter("ignore")
        print(json.dumps(child_first(args.manifold[0], args.preset, args.child_first)))
        return
    if args.first:
        first(args)
        return
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

"""Benchmark: generate the synthetic corpus per preset; print wall time and peak memory.

Usage: python benchmarks/bench_synthetic.py [small default paper] [--save DIR]

Each preset runs in a fresh subprocess so its peak resident memory (VmHWM) is its
own; tracemalloc's peak of traced (numpy) allocations is printed as well. Targets:
"small" in a few seconds, "default" well under a minute, "paper" within about a minute.
With --save, the time to write the cache file (Corpus.save) is measured too.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

from _common import peak_rss_mb, run_child_json
from _harness import Harness

ROOT = Path(__file__).resolve().parents[1]


def one(preset: str, save_dir: str | None) -> dict:
    sys.path.insert(0, str(ROOT))
    from engine.talker.synthetic_talker import SyntheticTalker, _lexicon

    t = time.perf_counter()
    _lexicon()  # word list + CMU dictionary, loaded once per process
    t_lex = time.perf_counter() - t
    tracemalloc.start()
    t = time.perf_counter()
    corpus = SyntheticTalker(preset=preset).generate()
    dt = time.perf_counter() - t
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    out = {"preset": preset, "lexicon_s": t_lex, "generate_s": dt, "frames": corpus.n_frames,
           "points": corpus.n_points, "coords": corpus.frames.shape[1], "utterances": len(corpus.utterances),
           "phones": sum(len(u.phones) for u in corpus.utterances), "seconds": corpus.duration,
           "frames_MiB": corpus.frames.nbytes / 2**20, "traced_peak_MiB": peak / 2**20}
    if save_dir:
        t = time.perf_counter()
        corpus.save(Path(save_dir) / f"{preset}.npz")
        out["save_s"] = time.perf_counter() - t
    out["max_rss_MiB"] = peak_rss_mb()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="*", default=["small", "default", "paper"])
    ap.add_argument("--save", metavar="DIR", help="also time Corpus.save into DIR")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    Harness.add_arguments(ap)
    args = ap.parse_args()
    if args.one:
        print(json.dumps(one(args.one, args.save)))
        return
    bench = Harness("bench_synthetic", args)
    print(f"{'preset':<8} {'frames':>7} {'points':>6} {'coords':>6} {'utts':>5} {'speech s':>8} "
          f"{'lexicon s':>9} {'generate s':>10} {'save s':>7} {'traced MiB':>10} {'max RSS MiB':>11}")
    with tempfile.TemporaryDirectory() as tmp:
        for preset in args.presets:
            cmd = [sys.executable, __file__, "--one", preset] + (["--save", args.save or tmp] if args.save else [])
            r = run_child_json(cmd)
            print(f"{preset:<8} {r['frames']:>7} {r['points']:>6} {r['coords']:>6} {r['utterances']:>5} "
                  f"{r['seconds']:>8.1f} {r['lexicon_s']:>9.2f} {r['generate_s']:>10.2f} "
                  f"{r.get('save_s', float('nan')):>7.2f} {r['traced_peak_MiB']:>10.1f} {r['max_rss_MiB']:>11.1f}",
                  flush=True)
            bench.figure(f"generate {preset}", r["generate_s"], cold=True, peak_rss_mib=r["max_rss_MiB"],
                         peak_traced_mib=r["traced_peak_MiB"], headline=True, frames=r["frames"],
                         lexicon_s=r["lexicon_s"], **({"save_s": r["save_s"]} if "save_s" in r else {}))
    bench.finish()


if __name__ == "__main__":
    main()

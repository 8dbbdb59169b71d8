"""Benchmark: the synthetic talker's speech audio, per-phone alignment against the word method.

Usage: python benchmarks/bench_speech_audio.py [--preset default] [--repeats 3] [--no-words]

1. Time (cold: a fresh process each repeat, files written into an empty folder) of
   ``add_speech_audio`` for the preset's corpus with each method: ``phones`` (espeak-ng's
   library, every phone placed on the talker's phone start) and ``words`` (the program,
   words placed on their spans), two espeak-ng processes at once; min and median of the
   repeats, peak memory of the process (and, in the analysis, of one library process).
2. For every utterance (phone method):
   - alignment error per phone, measured in the output: the first 12 ms after each phone
     event in espeak-ng's own sound is searched for (normalised cross-correlation,
     ±40 ms) around the talker's phone start in the warped sound (its earliest copy: a score
     within 0.05 of the best; stretching repeats a phone's first pitch periods); phones whose start is
     silent (a stop's closure) or whose template is no longer recognisable (score < 0.8)
     are counted apart;
   - an independent check: the steepest rise of the energy above 3 kHz within ±40 ms of
     each fricative/affricate's talker start (after a sound, not a pause), for both methods,
     and the same on espeak-ng's own sound at its own phone events (how far espeak-ng's
     events sit from the hiss it makes);
   - stretch factors (talker phone duration / espeak-ng's), pauses excluded;
   - clicks: the largest sample-to-sample jump within 2 samples of a phone boundary
     against the largest and the 99.9th percentile of all jumps inside phones.

The corpus comes from the cache (``LIPSPACE_CACHE_DIR``); its generation is not timed.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
FRICATIVES = ("s", "sh", "z", "zh", "f", "th", "ch", "jh")


def _corpus(preset):
    from engine.talker.synthetic import load_synthetic

    return load_synthetic(preset=preset)


def time_one(preset: str, method: str) -> dict:
    """In this (fresh) process: make the preset's audio with ``method`` into an empty folder."""
    from _common import peak_rss_mb

    from engine.phonetics import espeak_phones
    from engine.phonetics import speech_audio as sa

    corpus = _corpus(preset)
    if method == "words":
        espeak_phones.espeak_library = lambda: None
    assert sa.audio_method() == method, sa.audio_method()
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        c = sa.add_speech_audio(corpus, tmp, workers=2)
        dt = time.perf_counter() - t
    return {"method": method, "seconds": dt, "speech_s": corpus.duration, "utterances": len(corpus.utterances),
            "history": c.history[-1],
            "rss_MiB": peak_rss_mb()}


def template_errors(y, info, sr, template=0.012, search=0.04, min_score=0.8):
    """(errors s of the recognised phone starts, their phone indices, number silent, number unrecognised)."""
    x, src, dst = info["espeak"], info["source"], info["target"]
    n, m = int(template * sr), int(search * sr)
    level = np.sqrt(np.mean(x ** 2))
    errs, which, silent, lost = [], [], 0, 0
    for i, (s, t) in enumerate(zip(src[:-1].astype(int), np.round(dst[:-1]).astype(int))):
        tmpl = x[s:s + n]
        if len(tmpl) < n or np.sqrt(np.mean(tmpl ** 2)) < 0.3 * level:
            silent += 1
            continue
        a = max(t - m, 0)
        seg = y[a:t + m + n]
        c = np.correlate(seg, tmpl, mode="valid")
        energy = np.sqrt(np.convolve(seg ** 2, np.ones(n), mode="valid"))
        score = c / np.maximum(energy * np.linalg.norm(tmpl), 1e-9)
        if score.max() < min_score:
            lost += 1
            continue
        # the earliest copy: stretching repeats a phone's first pitch periods a period or two later
        errs.append((a + int(np.flatnonzero(score >= score.max() - 0.05)[0]) - t) / sr)
        which.append(i)
    return errs, which, silent, lost


def hiss_onset(y, t, sr, search=0.04):
    from scipy.signal import butter, sosfiltfilt

    hf = sosfiltfilt(butter(4, 3000, btype="high", fs=sr, output="sos"), y.astype(np.float64))
    n = int(0.005 * sr)
    env = np.log(np.sqrt(np.convolve(hf ** 2, np.ones(n) / n, mode="same")) + 1e-6)
    a, b = max(t - int(search * sr), 0), min(t + int(search * sr), len(y))
    rise = env[a + n:b] - env[a:b - n]
    return (a + n // 2 + int(np.argmax(rise)) - t) / sr


def analyse(preset: str, words: bool) -> dict:
    from _common import peak_rss_mb

    from engine.phonetics import espeak_phones
    from engine.phonetics import speech_audio as sa
    from engine.phonetics.phones import PAUSE

    sr = sa.SAMPLE_RATE
    corpus = _corpus(preset)
    errs, err_stretch, silent, lost, stretch, fallbacks = [], [], 0, 0, [], 0
    hiss = {"phones": [], "words": [], "espeak_at_its_events": []}
    joins, inside, source_jump = [], [], []
    with espeak_phones.EspeakWorker() as w:
        for u in corpus.utterances:
            y, info = sa.utterance_audio(u, worker=w)
            if info["method"] != "phones":
                fallbacks += 1
                continue
            e, idx, s, lo = template_errors(y, info, sr)
            errs += e
            err_stretch += [float(info["stretch"][i]) for i in idx]
            silent += s
            lost += lo
            k0 = next(k for k, p in enumerate(u.phones) if p.label != PAUSE)
            labels = [p.label for p in u.phones[k0:k0 + info["phones"]]]
            stretch += [f for f, lab in zip(info["stretch"], labels) if lab != PAUSE]
            d = np.abs(np.diff(y))
            b = np.round(info["target"]).astype(int)
            near = np.zeros(len(d), bool)
            for t in b:
                near[max(t - 3, 0):t + 2] = True
            joins.append(float(d[near[:len(d)]].max()))
            inside.append(d[~near])
            source_jump.append(float(np.abs(np.diff(info["espeak"])).max()))
            for j, (prev, p) in enumerate(zip(labels[:-1], labels[1:])):
                if p in FRICATIVES and prev != PAUSE:  # the same check on espeak-ng's own sound and events
                    hiss["espeak_at_its_events"].append(hiss_onset(info["espeak"], int(info["source"][j + 1]), sr))
            outs = {"phones": y}
            if words:
                outs["words"], _ = sa.utterance_audio(u, method="words")
            for name, yy in outs.items():
                for prev, p in zip(u.phones[:-1], u.phones[1:]):
                    if p.label in FRICATIVES and prev.label != PAUSE:
                        hiss[name].append(hiss_onset(yy, int(round(p.start * sr)), sr))
        worker_mib = peak_rss_mb(w._proc.pid)
    inside = np.concatenate(inside)
    a = np.abs(np.array(errs))
    st = np.array(stretch)
    out = {"utterances": len(corpus.utterances), "fallbacks": fallbacks, "library_process_peak_MiB": worker_mib,
           "aligned": len(errs), "silent_onsets": silent, "unrecognised": lost,
           "err_ms": {q: float(np.percentile(a, q) * 1000) for q in (50, 90, 95, 99, 100)},
           "err_within_6ms": float(np.mean(a <= 0.006)),
           "err_within_6ms_stretch_le_2": float(np.mean(a[np.array(err_stretch) <= 2] <= 0.006)),
           "err_within_6ms_stretch_gt_2": float(np.mean(a[np.array(err_stretch) > 2] <= 0.006)),
           "aligned_stretch_gt_2": int(np.sum(np.array(err_stretch) > 2)),
           "stretch": {q: float(np.percentile(st, q)) for q in (0, 5, 25, 50, 75, 95, 100)},
           "stretch_outside_0.5_2": float(np.mean((st < 0.5) | (st > 2.0))),
           "jump_at_joins_max": float(max(joins)), "jump_inside_max": float(inside.max()),
           "jump_inside_p999": float(np.percentile(inside, 99.9)), "jump_espeak_max": float(max(source_jump))}
    for name, v in hiss.items():
        if v:
            v = np.abs(np.array(v))
            out[f"hiss_{name}_ms"] = {"n": len(v), "median": float(np.median(v) * 1000),
                                      "p75": float(np.percentile(v, 75) * 1000),
                                      "within_5ms": float(np.mean(v <= 0.005))}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="default")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--no-words", action="store_true", help="skip the word method (timing and hiss check)")
    ap.add_argument("--time", nargs=2, metavar=("PRESET", "METHOD"), help=argparse.SUPPRESS)
    from _harness import Harness

    Harness.add_arguments(ap)
    args = ap.parse_args()
    if args.time:
        print(json.dumps(time_one(*args.time)))
        return
    from _common import run_child_json

    bench = Harness("bench_speech_audio", args)
    print(f"preset {args.preset}; load average at start {os.getloadavg()}")
    _corpus(args.preset)  # generated and cached once, not timed
    methods = (["phones"] + ([] if args.no_words else ["words"])) if args.repeats > 0 else []  # 0: analysis only
    for method in methods:
        runs = []
        for _ in range(args.repeats):
            load = os.getloadavg()[0]
            runs.append((run_child_json([sys.executable, __file__, "--time", args.preset, method]), load))
        secs = [r["seconds"] for r, _ in runs]
        r0 = runs[0][0]
        print(f"{method:<7} cold {r0['utterances']} utterances, {r0['speech_s']:.0f} s of speech: "
              f"min {min(secs):.2f} s, median {np.median(secs):.2f} s of {len(secs)} "
              f"(load {', '.join(f'{lo:.1f}' for _, lo in runs)}); "
              f"peak RSS {max(r['rss_MiB'] for r, _ in runs):.0f} MiB",
              flush=True)
        print(f"        {r0['history']}", flush=True)
        bench.figure(f"{method}: audio for the corpus", secs, cold=True,
                     peak_rss_mib=max(r["rss_MiB"] for r, _ in runs), headline=True, show=False,
                     speech_s=r0["speech_s"], utterances=r0["utterances"])
    t = time.perf_counter()
    res = analyse(args.preset, not args.no_words)
    print(f"analysis ({time.perf_counter() - t:.1f} s, load {os.getloadavg()[0]:.1f}):")
    print(json.dumps(res, indent=1))
    bench.fact(analysis=res)
    bench.finish()


if __name__ == "__main__":
    main()

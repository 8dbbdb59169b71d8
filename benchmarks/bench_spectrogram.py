"""Benchmark: a 60-s utterance's waveform and spectrogram, from Load until drawn under the timeline.

Usage: python benchmarks/bench_spectrogram.py [--seconds 60] [--repeats 5] [--cold 3]

The sound: ``--seconds`` of speech spoken by espeak-ng (22,050 Hz, 16-bit mono), the
talker's sentences one after another (without espeak-ng: the sample MOCHA recording in
``../shared/data``, repeated). The corpus: the small synthetic talker with its first
utterances joined into one utterance of ``--seconds`` (whose audio is that sound) and
a manifold fitted on it (not timed).

1. engine (:func:`engine.phonetics.spectrogram.sound_display` + ``grey()``: read the WAV, the
   Praat-style wide-band spectrogram 0-8 kHz, grey levels):
   - cold: a fresh process each time (imports included), ``--cold`` processes;
   - warm: ``--repeats`` calls in one process.
2. the explorer window (real ``MainWindow`` under an X server; re-runs itself under
   ``xvfb-run`` without one): wall time from pressing Load for the 60-s utterance in the
   trajectory editor until the panel under the timeline has painted its spectrogram
   (``SoundPanel.shown_at``), computed in a worker thread:
   - first: the first Load in the process (nothing cached);
   - uncached: ``--repeats`` more Loads with the editor's cache emptied before each;
   - cached: ``--repeats`` Loads of the same utterance again (the cache serves it).
   Also: whether the GUI thread stayed free meanwhile (the longest gap between two
   ticks of a 5-ms timer from Load until drawn), beside the same for a cached Load (the
   same work on the GUI thread — targets, painting — with no worker running).

Prints min / median / max, peak RSS and the BLAS kernel. Goal (issue 28 item 1): under 1 s.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
import _gui_bench as gb  # noqa: E402
from _common import peak_rss_mb  # noqa: E402
from _harness import Harness  # noqa: E402

MOCHA_WAV = HERE.parents[1] / "shared" / "data" / "mocha-fsew0" / "fsew0_001.wav"


def make_speech(path: Path, seconds: float) -> str:
    """Write ``seconds`` of speech to ``path`` (16-bit mono WAV); returns what it is."""
    from engine.files.atomic import write_wav_atomic
    from engine.phonetics.speech_audio import read_wav
    from engine.talker.synthetic import load_synthetic

    exe = shutil.which("espeak-ng")
    if exe is not None:
        text = " ".join(u.text for u in load_synthetic(preset="small").utterances if u.text)
        r = subprocess.run([exe, "-v", "en-us", "--stdout", text], capture_output=True, check=True, timeout=120)
        x, sr = read_wav(r.stdout)
        what = f"espeak-ng speech of the talker's sentences at {sr} Hz"
    elif MOCHA_WAV.is_file():
        x, sr = read_wav(MOCHA_WAV.read_bytes())
        what = f"the MOCHA sample {MOCHA_WAV.name} repeated, {sr} Hz (espeak-ng is not installed)"
    else:
        sys.exit("no speech: install espeak-ng or put the shared data beside the checkout")
    n = int(round(seconds * sr))
    x = np.tile(x, n // len(x) + 1)[:n]
    write_wav_atomic(path, x, sr)
    return what


def engine_once(path) -> float:
    from engine.phonetics.spectrogram import sound_display

    t = time.perf_counter()
    d = sound_display(path)
    d.spectrogram.grey()
    return time.perf_counter() - t


def long_utterance_manifold(wav: Path, seconds: float):
    """The small talker with its first utterances joined into one of ``seconds`` whose audio is ``wav``."""
    from dataclasses import replace

    from engine.manifold.model import Manifold
    from engine.recordings.corpus import PhoneInterval, Utterance
    from engine.talker.synthetic import load_synthetic

    c = load_synthetic(preset="small")
    n = int(round(seconds * c.rate))
    if c.n_frames < n + 200:
        sys.exit(f"the small talker has {c.n_frames} frames; {seconds} s needs {n + 200}")
    phones = []
    for u in c.utterances:
        if u.start >= n:
            break
        t0 = u.start / c.rate
        phones += [PhoneInterval(t0 + p.start, min(t0 + p.end, n / c.rate), p.label) for p in u.phones
                   if t0 + p.start < n / c.rate]
    long = Utterance("long", 0, n, phones=tuple(phones), audio=str(wav), text=f"{seconds:g} s of speech")
    rest = Utterance("rest", n, c.n_frames)
    c = replace(c, utterances=[long, rest])
    return Manifold().fit(c)


def gui(manifold, repeats: int) -> dict:
    from PySide6 import QtCore

    app, win = gb.open_window(manifold, {"path": None})
    ed = win.editor
    ed.set_source("utterance")
    ed.utt_box.setCurrentIndex(ed.utt_box.findData("long"))
    gaps: list[float] = []
    last = [time.perf_counter()]

    def tick():
        t = time.perf_counter()
        gaps.append(t - last[0])
        last[0] = t

    timer = QtCore.QTimer()
    timer.setInterval(5)
    timer.timeout.connect(tick)

    def load_until_shown(clear: bool) -> float:
        if clear:
            ed.sound_track.clear_cache()
        ed.sound_track.show(None)  # as when another input was shown before
        gb.settle(app, 0.2)
        last[0] = time.perf_counter()
        timer.start()
        t0 = time.perf_counter()
        ed.load()
        while ed.sound.shown_at is None:
            app.processEvents()
            time.sleep(0.0005)
            if time.perf_counter() - t0 > 60:
                sys.exit(f"no spectrogram within 60 s ({ed.sound_track.error})")
        timer.stop()
        return ed.sound.shown_at - t0

    first = load_until_shown(True)
    first_gap = max(gaps, default=0.0)
    uncached, worst = [], []
    for _ in range(repeats):
        gaps.clear()
        uncached.append(load_until_shown(True))
        worst.append(max(gaps, default=0.0))
    cached, cached_gaps = [], []
    for _ in range(repeats):
        gaps.clear()
        cached.append(load_until_shown(False))
        cached_gaps.append(max(gaps, default=0.0))
    spec = ed.sound.display.spectrogram
    out = {"first": first, "first_gap": first_gap, "uncached": uncached, "gaps": worst, "cached": cached,
           "cached_gaps": cached_gaps, "shape": list(spec.power_db.shape), "width": ed.sound.width(),
           "seconds": ed.sound.display.duration}
    win.close()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--cold", type=int, default=3, help="fresh processes for the cold engine figure")
    ap.add_argument("--child", metavar="WAV", help=argparse.SUPPRESS)
    Harness.add_arguments(ap)
    args = ap.parse_args()
    if args.child:  # one fresh process: the engine computation, imports included
        t = time.perf_counter()
        engine_once(args.child)
        print(json.dumps({"s": time.perf_counter() - t}))
        return
    gb.ensure_display()
    bench = Harness("bench_spectrogram", args)
    gb.header(f"{args.seconds:g}-s utterance: waveform and spectrogram, Load -> drawn")
    with tempfile.TemporaryDirectory(prefix="lipspace-bench-spec-") as tmp:
        wav = Path(tmp) / "long.wav"
        what = make_speech(wav, args.seconds)
        print(f"   sound: {args.seconds:g} s, {what}; {wav.stat().st_size / 2**20:.1f} MiB")
        cold = []
        for _ in range(args.cold):
            p = subprocess.run([sys.executable, __file__, "--child", str(wav)], capture_output=True, text=True,
                               env=os.environ, timeout=300)
            if p.returncode:
                sys.exit(f"cold child failed:\n{p.stderr[-2000:]}")
            cold.append(json.loads(p.stdout.strip().splitlines()[-1])["s"])
        engine_once(wav)  # warm-up
        warm = [engine_once(wav) for _ in range(args.repeats)]
        print(f"engine, cold (fresh process, imports included, {args.cold} processes): {gb.stats(cold)}")
        print(f"engine, warm ({args.repeats} calls in one process):                    {gb.stats(warm)}")
        bench.figure("engine, cold (fresh process)", cold, cold=True, show=False)
        bench.figure("engine, warm", warm, cold=False, show=False)
        t = time.perf_counter()
        m = long_utterance_manifold(wav, args.seconds)
        print(f"   manifold for the window: small talker, one {args.seconds:g}-s utterance, {m.Fy_.shape[0]} frames "
              f"(fitted in {time.perf_counter() - t:.1f} s, not timed)")
        r = gui(m, args.repeats)
    print(f"   spectrogram {r['shape'][0]} bands x {r['shape'][1]} frames; panel {r['width']} px wide; "
          f"audio {r['seconds']:.2f} s")
    print(f"window, first Load in the process (nothing cached): {1e3 * r['first']:.1f} ms; longest GUI-thread gap "
          f"meanwhile {1e3 * r['first_gap']:.1f} ms")
    print(f"window, uncached (cache emptied before each Load): {gb.stats(r['uncached'])}")
    print(f"   longest GUI-thread gap during each (5-ms timer): {gb.stats(r['gaps'])}")
    print(f"window, cached (the same utterance again):         {gb.stats(r['cached'])}")
    print(f"   longest GUI-thread gap during each (the same GUI work, no worker): {gb.stats(r['cached_gaps'])}")
    print(f"peak RSS {peak_rss_mb():.0f} MiB")
    bench.figure("window, first Load", r["first"], cold=True, show=False)
    bench.figure("window, Load -> drawn, uncached", r["uncached"], headline=True, show=False)
    bench.figure("window, Load -> drawn, cached", r["cached"], headline=True, show=False)
    bench.figure("window, longest GUI-thread gap, uncached", r["gaps"], show=False)
    bench.fact(seconds=r["seconds"], bands=r["shape"][0], frames=r["shape"][1])
    bench.finish()


if __name__ == "__main__":
    main()

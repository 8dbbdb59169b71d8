"""Make the large manifolds the GUI benchmarks open with ``--manifold``: the synthetic talker at 100k-10M frames.

Each size is built the way ``benchmarks/bench_scale.py`` builds it: the talker speaks N frames at
60 Hz (156 points, ``--resolution small``), written as a corpus stored in blocks
(8,192 frames per block) in a fresh process; a second fresh process opens that corpus
lazily, fits ``Manifold()`` with the default size rule (2,000 landmarks above 50,000
frames) in-process or on Dask (``--dask local`` or a scheduler's address) and saves
the manifold, which references the blocked corpus. Printed per size: the build's
wall time and client CPU per stage, the client's peak memory (and the workers'), and
the manifold file to pass to ``bench_gui_*.py --manifold``. Files already made are
reused (``--rebuild`` builds the manifold again).

Above ``--chunk-frames`` (default 1,000,000) the talker is generated in parts of that
many frames, each in its own process and with its own seed and speaker name
(``spk01``, ``spk02``, ...: as a lab pools several speakers' recordings; the build
normalises them per speaker), and the parts' blocks are joined into one blocked corpus
without reading them. The parts' per-frame ground truth (the talker's latent controls)
is dropped from the joined corpus: nothing of the explorer reads it, and at 10M frames
it would add 0.6 GB to both the corpus and the manifold file. Disk: 1.87 GB of frames
per million frames, plus the manifold file (about 0.84 GB per million frames).

Usage::

    python tools/make_standins.py                                     # 100k, 300k, 1M in /tmp/lipspace-standins
    python tools/make_standins.py --sizes 10000000 --dask local       # the 10M stand-in (long; ~20 GB on disk)
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(ROOT, "benchmarks"))  # _common and bench_scale
from _common import run_child_json  # noqa: E402


def corpus_path(work: str, n: int, resolution: str) -> str:
    return os.path.join(work, f"talker-{n}-{resolution}.npz")


def manifold_path(work: str, n: int, resolution: str) -> str:
    return corpus_path(work, n, resolution)[:-len(".npz")] + "-manifold.npz"


def generate_part(n_frames: int, resolution: str, seed: int, speaker: str, path: str) -> dict:
    """One part of a chunked stand-in: ``n_frames`` of the talker with ``seed``, spoken by ``speaker``."""
    from dataclasses import replace

    from engine.recordings.corpus_blocks import save_blocked
    from engine.talker.synthetic import SyntheticTalker

    t = time.perf_counter()
    c = SyntheticTalker(duration=n_frames / 60.0, resolution=resolution, seed=seed).generate()
    c.utterances = [replace(u, id=f"{speaker}_{u.id}", speaker=speaker) for u in c.utterances]
    c.latent = {}
    c.history = [*c.history, f"part {seed} of a pooled stand-in, speaker {speaker}"]
    save_blocked(c, path)
    return {"generate_s": time.perf_counter() - t}


def join_parts(parts: list[str], out: str) -> None:
    """Join blocked corpora (same points, rate and roles) into one, moving their block files (no frame is read)."""
    import numpy as np

    from engine.files.atomic import atomic_write
    from engine.recordings.corpus_blocks import blocks_folder, load_blocked

    folder = blocks_folder(out)
    folder.mkdir(parents=True, exist_ok=True)
    joined: dict = {}
    frames = utts = 0
    files, counts = [], []
    for part in parts:
        with np.load(part) as z:
            d = {k: z[k] for k in z.files}
        src = blocks_folder(part)
        for name, n in zip(d["blocks_files"], d["blocks_frames"]):
            new = f"block_{len(files):05d}.npy"
            os.replace(src / str(name), folder / new)
            files.append(new)
            counts.append(int(n))
        d["corpus_utt_bounds"] = d["corpus_utt_bounds"] + frames
        d["corpus_phone_utt"] = d["corpus_phone_utt"] + utts
        frames += int(d["corpus_n_frames"])
        utts += len(d["corpus_utt_ids"])
        for k, v in d.items():
            if k.startswith("corpus_utt_") or k.startswith("corpus_phone_"):
                joined.setdefault(k, []).append(v)
            elif k not in joined and not k.startswith("blocks_") and not k.startswith("corpus_latent_"):
                joined[k] = v
    arrays = {k: (np.concatenate(v) if isinstance(v, list) else v) for k, v in joined.items()}
    arrays["corpus_n_frames"] = np.array(frames)
    arrays["corpus_name"] = np.array(f"pooled synthetic talker ({len(parts)} speakers, {frames} frames)")
    arrays["corpus_history"] = np.array([f"joined from {len(parts)} parts of {frames // len(parts)} frames, "
                                         "one speaker each (make_standins.py)"], dtype=str)
    arrays["blocks_files"] = np.array(files, dtype=str)
    arrays["blocks_frames"] = np.array(counts, dtype=np.int64)
    with atomic_write(out) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)
    load_blocked(out)  # every block and field checked as the build will read them
    for part in parts:
        os.unlink(part)
        shutil.rmtree(blocks_folder(part), ignore_errors=True)


def make_corpus(n: int, args, me) -> str:
    path = corpus_path(args.work, n, args.resolution)
    if os.path.isfile(path):
        print(f"{n} frames: corpus {path} (reused)", flush=True)
        return path
    t = time.perf_counter()
    if n <= args.chunk_frames:
        r = run_child_json(me + ["--generate", str(n), "--one", path, "--resolution", args.resolution])
        print(f"{n} frames: corpus generated in {r['generate_s']:.1f} s -> {path}", flush=True)
        return path
    parts, left, k = [], n, 0
    while left > 0:
        size = min(args.chunk_frames, left)
        part = os.path.join(args.work, f"part-{n}-{k:02d}.npz")
        if not os.path.isfile(part):
            r = run_child_json(me + ["--part", str(size), "--seed", str(k), "--speaker", f"spk{k + 1:02d}",
                                     "--one", part, "--resolution", args.resolution])
            print(f"   part {k + 1}: {size} frames generated in {r['generate_s']:.1f} s", flush=True)
        parts.append(part)
        left -= size
        k += 1
    join_parts(parts, path)
    print(f"{n} frames: corpus of {len(parts)} parts made in {time.perf_counter() - t:.1f} s -> {path}", flush=True)
    return path


def main(argv=None) -> int:
    import bench_scale

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    bench_scale.add_build_arguments(ap, sizes=[100000, 300000, 1000000], work="lipspace-standins",
                                    what="the corpora and manifolds")
    ap.add_argument("--chunk-frames", type=int, default=1_000_000,
                    help="larger stand-ins are generated in parts of this many frames, one speaker each")
    ap.add_argument("--rebuild", action="store_true", help="build the manifold again even when it exists")
    ap.add_argument("--corpus-only", action="store_true", help="make the blocked corpora, build nothing")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    ap.add_argument("--generate", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--part", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--seed", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--speaker", default="", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.generate:
        print(json.dumps(bench_scale.generate(args.generate, args.resolution, args.one)))
        return 0
    if args.part:
        print(json.dumps(generate_part(args.part, args.resolution, args.seed, args.speaker, args.one)))
        return 0
    os.makedirs(args.work, exist_ok=True)
    me = [sys.executable, os.path.abspath(__file__)]
    scale = [sys.executable, os.path.abspath(bench_scale.__file__)]
    made = []
    for n in args.sizes:
        path = make_corpus(n, args, me)
        if args.corpus_only:
            continue
        out = manifold_path(args.work, n, args.resolution)
        if os.path.isfile(out) and not args.rebuild:
            print(f"   manifold {out} (reused; --rebuild builds it again)", flush=True)
            made.append(out)
            continue
        r = run_child_json(scale + ["--one", path] + (["--dask", args.dask] if args.dask else []))
        wall = ", ".join(f"{k} {v:.1f}" for k, v in r["stages"].items())
        cpu = ", ".join(f"{k} {v:.1f}" for k, v in r.get("stage_cpu", {}).items())
        workers = r.get("worker_peak_mb") or []  # None: built in this process, no workers
        peaks = ", ".join(f"{w:.0f}" for w in workers)
        wk = f"; workers' peak RSS {peaks} MB" if workers else ""
        print(f"   {r['plan']}\n   build {r['wall_s']:.1f} s wall, client CPU {r['cpu_s']:.1f} s; per stage, wall (s): "
              f"{wall}\n   client CPU per stage (s): {cpu or 'n/a'}\n   client peak RSS {r['rss_peak_mb']:.0f} MB{wk}; "
              f"saved {r['saved']['mb']:.0f} MB in {r['saved']['s']:.1f} s; load average {r['load_before'][0]:.1f} "
              f"before, {r['load_after'][0]:.1f} after; BLAS {r['blas']}", flush=True)
        made.append(out)
    print("manifolds (for bench_gui_startup.py / bench_gui_click.py / bench_gui_playback.py --manifold):")
    for out in made:
        print(f"   {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Wall time and memory per stage of the whole build at growing N, the client's apart from the workers' (issue 13).

For each N the synthetic talker speaks N frames (60 Hz) in a fresh process that writes
them as a corpus stored in blocks (``engine.recordings.corpus_blocks.save_blocked``, 8,192 frames
per block, kept in ``--work`` and reused by later runs); then a second fresh process
(cold) opens that corpus lazily (``load_blocked``: block paths and per-utterance
metadata, no frames), builds its manifold with ``Manifold().fit`` and saves it (the file
references the blocked corpus). The build follows the size rule of ``engine.manifold.buildplan``:
the exact embedding up to 50,000 frames, 2,000 landmarks above.

Printed per size: the path taken; wall time per stage; the client process's resident
memory after opening the corpus, and its peak in every stage (sampled every 10 ms;
the stage is the one the build last reported through its progress callback: "setup"
is the speaker normalisation before the shape space, the lip aperture falls in
"tangent frames"); the size of N x C float32 frames beside it (what the client would
hold if it gathered the corpus); with ``--dask`` the workers' peak resident memory, each
over the worker's whole life; the saved file's size. At the end the fitted exponent b
of ``memory ~ N^b`` and ``time ~ N^b`` over the sizes (memory linear in N: b <= 1).

``--shape-only`` times only the build's first stages, the speaker normalisation and the
shape space (F^x), where the Dask workers read every block of F several times; with
``--dask local`` the cluster can be given ``--workers`` single-threaded workers of
``--worker-memory`` each. ``--repeat`` measures every size that many times, each in a
fresh process (and a fresh local cluster), and prints the min and median; ``--against
DIR`` runs every measurement also with the ``engine`` of another source tree (e.g. the
commit before a change, ``git archive REV | tar -x -C DIR``), alternating with this one.

Points per frame: ``--resolution small`` (156 points, 468 coordinates) by default for
every size so that the sizes are comparable; ``--resolution paper`` gives the paper's
4,260 points (12,780 coordinates; 1.5 GB of frames at 30k).

Usage::

    python benchmarks/bench_scale.py                          # 30k, 100k, 300k, in-process
    python benchmarks/bench_scale.py --sizes 30000 100000 300000 1000000 --dask local
    python benchmarks/bench_scale.py --sizes 30000 --resolution paper --dask local
    python benchmarks/bench_scale.py --sizes 1000000 --shape-only --dask local --workers 1 \
        --worker-memory 4GB --repeat 2 --against /tmp/lipspace-before
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import blas_kernel, current_rss_mb, peak_rss_mb, run_child_json  # noqa: E402
from _harness import Harness  # noqa: E402


class _StagePeaks(threading.Thread):
    """Highest VmRSS seen while running (sampled every ``interval`` s), overall and in every
    stage the build reports (``progress``)."""

    def __init__(self, interval=0.01):
        super().__init__(daemon=True)
        self.interval, self.peak, self._halt = interval, current_rss_mb(), threading.Event()
        self.stage, self.stages = "setup", {}
        self.cpu, self._cpu0 = {}, time.process_time()  # the client's CPU seconds per reported stage

    def progress(self, stage, done, total):
        if stage and stage != self.stage:
            self.stages[self.stage] = max(self.stages.get(self.stage, 0.0), current_rss_mb())
            now = time.process_time()
            self.cpu[self.stage] = self.cpu.get(self.stage, 0.0) + now - self._cpu0
            self._cpu0 = now
            self.stage = stage

    def run(self):
        while not self._halt.is_set():
            rss = current_rss_mb()
            self.peak = max(self.peak, rss)
            self.stages[self.stage] = max(self.stages.get(self.stage, 0.0), rss)
            time.sleep(self.interval)

    def stop(self) -> float:
        self._halt.set()
        self.join()
        self.peak = max(self.peak, current_rss_mb())
        return self.peak


def connect(dask: str, *, workers: int | None = None, worker_memory: str | None = None):
    """A ``DaskExecutor`` for ``dask``; for ``"local"`` with ``workers`` or ``worker_memory``: a
    LocalCluster of that many single-threaded workers (default: one per core), each limited
    to ``worker_memory`` (default: the machine's memory split evenly)."""
    from engine.scale.executor import DaskExecutor

    if dask != "local" or (workers is None and worker_memory is None):
        return DaskExecutor.connect(dask)
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                           memory_limit=worker_memory or "auto", dashboard_address=":0")
    return DaskExecutor(Client(cluster), own_cluster=True)


def fit_shape_only(corpus, *, executor=None, progress=None):
    """The build's first stages only, as ``Manifold().fit`` runs them: the speaker normalisation
    and the shape space with ``Manifold()``'s settings; returns F^x (N, m)."""
    from engine.manifold.model import Manifold
    from engine.manifold.shape import ShapeSpace
    from engine.recordings.registration import normalise_speakers

    m = Manifold()
    corpus = normalise_speakers(corpus, mode=m.speaker_normalisation, executor=executor)
    shape = ShapeSpace(max_components=m.max_components, variance=m.variance, random_state=m.random_state)
    if executor is None:
        return shape.fit(corpus.frames, progress=progress).transform(corpus.frames)
    return executor.fit_shape(shape, corpus.frames, progress=progress)


def _worker_facts(executor) -> list:
    """``"ENGINE_TREE; BLAS ..."`` of every worker (distinct ones): which source tree ran the tasks,
    on which BLAS kernel and threads (a worker's BLAS runs one thread per worker thread)."""
    def facts():
        from threadpoolctl import threadpool_info

        import engine

        blas = "; ".join(f"{i.get('internal_api')} {i.get('version')} kernel={i.get('architecture')} "
                         f"threads={i.get('num_threads')}" for i in threadpool_info() if i.get("user_api") == "blas")
        return f"{os.path.dirname(os.path.dirname(os.path.abspath(engine.__file__)))}; BLAS {blas or 'none found'}"

    return sorted(set(executor.client.run(facts).values()))


def measured_build(corpus, dask: str | None, *, save_to=None, shape_only=False, workers=None,
                   worker_memory=None) -> dict:
    """``Manifold().fit(corpus)`` (on Dask when ``dask`` names a cluster), measured: the manifold,
    wall and client CPU seconds, resident memory at the start and peak (MB), the client's peak per
    stage, the workers' peaks; with ``save_to`` the manifold is saved there too (stage "save").
    ``shape_only``: :func:`fit_shape_only` instead (the manifold is None, nothing is saved)."""
    import warnings

    from engine.manifold.model import Manifold

    executor = connect(dask, workers=workers, worker_memory=worker_memory) if dask else None
    start = current_rss_mb()
    sampler = _StagePeaks()
    sampler.start()
    c0, t = time.process_time(), time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # connectivity warnings of the state graph are not the point here
        if shape_only:
            fit_shape_only(corpus, executor=executor, progress=sampler.progress)
            m = None
        else:
            m = Manifold().fit(corpus, executor=executor, progress=sampler.progress)
    wall, cpu = time.perf_counter() - t, time.process_time() - c0
    saved = None
    if save_to is not None and m is not None:
        sampler.progress("save", 0, 1)
        t = time.perf_counter()
        m.save(save_to)
        saved = {"s": time.perf_counter() - t, "mb": os.path.getsize(save_to) / 2**20}
    sampler.progress("end", 0, 1)
    peak = sampler.stop()
    workers = engines = None
    if executor is not None:
        workers = sorted(peak_rss_mb(pid) for pid in executor.client.run(os.getpid).values())
        engines = _worker_facts(executor)
        executor.close()
    return {"manifold": m, "wall": wall, "cpu": cpu, "start": start, "peak": peak, "workers": workers,
            "worker_engines": engines, "stage_peaks": sampler.stages, "stage_cpu": sampler.cpu, "saved": saved}


def generate(n_frames: int, resolution: str, path: str) -> dict:
    """The talker's N frames written as a blocked corpus at ``path`` (run in a fresh process)."""
    from engine.recordings.corpus_blocks import save_blocked
    from engine.talker.synthetic import SyntheticTalker

    t = time.perf_counter()
    corpus = SyntheticTalker(duration=n_frames / 60.0, resolution=resolution).generate()
    save_blocked(corpus, path)
    return {"generate_s": time.perf_counter() - t}


def one(path: str, dask: str | None, *, shape_only=False, workers=None, worker_memory=None) -> dict:
    """Open the blocked corpus at ``path`` lazily, build, save, and measure (run in a fresh process);
    ``shape_only``: only :func:`fit_shape_only`, nothing saved."""
    import engine
    from engine.manifold.buildplan import plan_build
    from engine.recordings.corpus_blocks import load_blocked

    load0 = os.getloadavg()
    rss0 = current_rss_mb()
    t = time.perf_counter()
    corpus = load_blocked(path)
    t_open = time.perf_counter() - t
    out = None if shape_only else path[:-len(".npz")] + "-manifold.npz"
    b = measured_build(corpus, dask, save_to=out, shape_only=shape_only, workers=workers, worker_memory=worker_memory)
    m = b["manifold"]
    return {"n_frames": corpus.n_frames, "coords": corpus.frames.shape[1], "blocks": len(corpus.frames.paths),
            "speakers": len(corpus.speakers), "open_s": t_open, "rss_before_open_mb": rss0,
            "plan": plan_build(corpus.n_frames).describe(), "wall_s": b["wall"], "cpu_s": b["cpu"],
            "stages": m.timings_ if m is not None else {}, "rss_start_mb": b["start"], "rss_peak_mb": b["peak"],
            "build_mb": b["peak"] - b["start"], "stage_peaks_mb": b["stage_peaks"], "stage_cpu": b["stage_cpu"],
            "saved": b["saved"], "engine": os.path.dirname(os.path.dirname(os.path.abspath(engine.__file__))),
            "worker_peak_mb": b["workers"], "worker_engines": b["worker_engines"],
            "frames_mb": corpus.frames.nbytes / 2**20, "blas": blas_kernel(),
            "dask": dask, "load_before": load0, "load_after": os.getloadavg()}


def _exponent(ns, ys):
    import numpy as np

    ns, ys = np.log(np.asarray(ns, float)), np.log(np.maximum(np.asarray(ys, float), 1e-9))
    return float(np.polyfit(ns, ys, 1)[0]) if len(ns) > 1 else float("nan")


def add_build_arguments(ap, *, sizes, work: str, what: str) -> None:
    """``--sizes``, ``--resolution``, ``--dask`` and ``--work`` (default ``$TMPDIR/work``, holding ``what``)."""
    ap.add_argument("--sizes", type=int, nargs="+", default=list(sizes))
    ap.add_argument("--resolution", default="small", help="lip model resolution (small: 156 points, paper: 4,260)")
    ap.add_argument("--dask", default=None, help="'local' or a scheduler address (default: in-process)")
    ap.add_argument("--work", default=os.path.join(os.environ.get("TMPDIR", "/tmp"), work),
                    help=f"folder for {what} (default: %(default)s)")


def _child_command(me, path, args, root) -> tuple[list, dict]:
    """The measuring child's command and environment (``root``: another tree's ``engine``, first on its path)."""
    cmd = me + ["--one", path] + (["--dask", args.dask] if args.dask else [])
    cmd += ["--shape-only"] if args.shape_only else []
    cmd += ["--workers", str(args.workers)] if args.workers else []
    cmd += ["--worker-memory", args.worker_memory] if args.worker_memory else []
    env = dict(os.environ)
    if root:  # the local cluster's workers are spawned with the child's sys.path; PYTHONPATH for any other
        cmd += ["--root", root]
        env["PYTHONPATH"] = os.pathsep.join([root] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return cmd, env


def _print_build(r, gen: str) -> None:
    st = ", ".join(f"{k} {v:.1f}" for k, v in r["stages"].items())
    peaks = ", ".join(f"{k} {v:.0f}" for k, v in r["stage_peaks_mb"].items() if k != "end")
    cpu = ", ".join(f"{k} {v:.1f}" for k, v in r["stage_cpu"].items())
    wk = f"\n  workers' peak RSS {', '.join(f'{w:.0f}' for w in r['worker_peak_mb'])} MB" if r["worker_peak_mb"] else ""
    sv = r["saved"]
    print(f"{r['plan']}\n  {r['coords']} coordinates, {r['speakers']} speaker(s), {r['blocks']} blocks "
          f"({r['frames_mb']:.0f} MB of frames, {gen}); opened in {r['open_s']:.2f} s\n"
          f"  build {r['wall_s']:.1f} s wall, client CPU {r['cpu_s']:.1f} s ({st}); saved in {sv['s']:.1f} s "
          f"({sv['mb']:.0f} MB file)\n  client CPU per reported stage (s): {cpu}\n"
          f"  client RSS after opening the corpus {r['rss_start_mb']:.0f} MB, peak {r['rss_peak_mb']:.0f} MB "
          f"(N x C frames would be {r['frames_mb']:.0f} MB); peak per stage (MB): {peaks}{wk}\n"
          f"  load average {r['load_before'][0]:.1f} before, {r['load_after'][0]:.1f} after "
          f"({os.cpu_count()} cores)", flush=True)


def _print_shape(r, label: str) -> None:
    wk = ", ".join(f"{w:.0f}" for w in r["worker_peak_mb"]) if r["worker_peak_mb"] else "-"
    print(f"{r['n_frames']} frames ({r['blocks']} blocks, {r['frames_mb']:.0f} MB), shape space only, {label}: "
          f"{r['wall_s']:.1f} s wall, client CPU {r['cpu_s']:.1f} s; workers' peak RSS {wk} MB; client peak "
          f"{r['rss_peak_mb']:.0f} MB; load average {r['load_before'][0]:.1f} before, {r['load_after'][0]:.1f} "
          f"after; engine {r['engine']}; workers: {' | '.join(r['worker_engines'] or ['-'])}", flush=True)


def _print_summary(runs: dict) -> None:
    """Min and median of the wall time and the largest worker peak, per size and source tree."""
    import numpy as np

    for (n, label), rs in runs.items():
        wall = [r["wall_s"] for r in rs]
        wk = [max(r["worker_peak_mb"]) for r in rs if r["worker_peak_mb"]]
        mem = f"; worker peak RSS min {min(wk):.0f}, median {np.median(wk):.0f} MB" if wk else ""
        print(f"  {n} frames, {label}, {len(rs)} runs: wall min {min(wall):.1f}, median {np.median(wall):.1f} s{mem}")


def _print_exponents(runs: list) -> None:
    ns = [r["n_frames"] for r in runs]
    print(f"fitted exponents over N = {ns}: client build memory ~ N^"
          f"{_exponent(ns, [r['build_mb'] for r in runs]):.2f}, client peak RSS ~ N^"
          f"{_exponent(ns, [r['rss_peak_mb'] for r in runs]):.2f}, wall ~ N^"
          f"{_exponent(ns, [r['wall_s'] for r in runs]):.2f}")
    if runs[0]["worker_peak_mb"]:
        print(f"  workers' largest peak RSS ~ N^{_exponent(ns, [max(r['worker_peak_mb']) for r in runs]):.2f}")
    for k in runs[0]["stages"]:
        print(f"  {k}: wall ~ N^{_exponent(ns, [r['stages'][k] for r in runs]):.2f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_build_arguments(ap, sizes=[30000, 100000, 300000], work="lipspace-bench-scale",
                        what="the blocked corpora (reused) and the manifolds")
    ap.add_argument("--shape-only", action="store_true",
                    help="time only the speaker normalisation and the shape space (nothing saved)")
    ap.add_argument("--workers", type=int, help="with --dask local: this many single-threaded workers")
    ap.add_argument("--worker-memory", help="with --dask local: each worker's memory limit (e.g. 4GB)")
    ap.add_argument("--repeat", type=int, default=1, help="measurements per size (default: %(default)s)")
    ap.add_argument("--against", help="also measure with the engine of this source tree, alternating")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    ap.add_argument("--root", help=argparse.SUPPRESS)
    ap.add_argument("--generate", type=int, help=argparse.SUPPRESS)
    Harness.add_arguments(ap)
    args = ap.parse_args(argv)
    if (args.workers or args.worker_memory) and args.dask != "local":
        ap.error("--workers and --worker-memory need --dask local")
    if args.root:
        sys.path.insert(0, os.path.abspath(args.root))
    if args.generate:
        print(json.dumps(generate(args.generate, args.resolution, args.one)))
        return 0
    if args.one:
        print(json.dumps(one(args.one, args.dask, shape_only=args.shape_only, workers=args.workers,
                             worker_memory=args.worker_memory)))
        return 0
    bench = Harness("bench_scale", args)
    os.makedirs(args.work, exist_ok=True)
    runs, by_tree = [], {}
    me = [sys.executable, os.path.abspath(__file__)]
    trees = [None] + ([os.path.abspath(args.against)] if args.against else [])
    for n in args.sizes:
        path = os.path.join(args.work, f"talker-{n}-{args.resolution}.npz")
        gen = "reused"
        if not os.path.isfile(path):
            made = run_child_json(me + ['--generate', str(n), '--one', path, '--resolution', args.resolution])
            gen = f"generated in {made['generate_s']:.1f} s"
        for i in range(max(1, args.repeat)):
            for root in trees if i % 2 == 0 else trees[::-1]:  # alternating: neither tree always runs first
                cmd, env = _child_command(me, path, args, root)
                r = run_child_json(cmd, env=env)
                label = "this tree" if root is None else f"against {root}"
                by_tree.setdefault((n, label), []).append(r)
                if root is None and i == 0:
                    runs.append(r)
                _print_shape(r, label) if args.shape_only else _print_build(r, gen)
    if runs:
        print(f"BLAS: {runs[0]['blas']}; dask: {args.dask or 'no (in-process)'}"
              + (f", {args.workers or 'one per core'} worker(s) of {args.worker_memory or 'auto'}"
                 if args.dask == "local" else ""))
    if args.repeat > 1 or args.against:
        _print_summary(by_tree)
    if len(runs) > 1:
        _print_exponents(runs)
    for (n, label), rs in by_tree.items():
        wk = [max(r["worker_peak_mb"]) for r in rs if r["worker_peak_mb"]]
        bench.figure(f"{n} frames, {label}: {'shape space' if args.shape_only else 'build'} wall",
                     [r["wall_s"] for r in rs], cold=True, peak_rss_mib=max(r["rss_peak_mb"] for r in rs),
                     headline=label == "this tree", show=False, worker_peak_mib=max(wk) if wk else None,
                     stages=rs[0]["stages"])
    bench.finish()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Probe: is a thread charged CPU time it did not use (hypervisor steal, or time the host took unreported)?

Usage: python tools/steal_probe.py [--seconds 60] [--interval 0.01] [--out FILE.npy]

Runs a fixed piece of work (sorting the same 8,192 doubles four times, about 0.2 ms)
every ``--interval`` seconds and records, per piece: the monotonic time, the thread's own
CPU clock (``time.thread_time``, exact), its run-queue wait (``/proc/thread-self/schedstat``)
and the hypervisor steal reported for the core it ran on (``/proc/stat``, 10-ms steps;
the kernel adds steal at its next timer tick, so the steal up to the next piece's start is
kept too). The work does not change, so a piece whose own CPU is many times the median
was charged time it did not use: the pieces are split by whether steal was reported on
their core by then. Prints the split, the totals (wall, own CPU, run-queue wait, steal),
load average and the BLAS kernel line. ``--out`` saves one row per piece
(start, end, own CPU s, wait s, core, steal s during, steal s by the next piece) for
lining up with other measurements on the same clock (``bench_gui_playback.py --probe``).
Stops cleanly on SIGTERM or Ctrl-C (and still saves).
"""
from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "benchmarks"))
from _playback_trace import parse_proc_stat, parse_task_stat  # noqa: E402

#: a piece of work is "charged" when its own CPU exceeds this many times the median
CHARGED_FACTOR = 10.0


def _reading(tid: int) -> tuple[int, tuple, float]:
    """(core, steal per core s, run-queue wait s) of thread ``tid`` now."""
    with open(f"/proc/self/task/{tid}/stat") as fh:
        core = parse_task_stat(fh.read())[0]
    with open("/proc/stat") as fh:
        steal, _ = parse_proc_stat(fh.read())
    with open("/proc/thread-self/schedstat") as fh:
        wait = int(fh.read().split()[1]) * 1e-9
    return core, steal, wait


def probe(seconds: float, interval: float, stop=lambda: False) -> np.ndarray:
    """Rows (start, end, own CPU, wait, core, steal during, steal by the next piece), one per piece."""
    tid = threading.get_native_id()
    work = np.random.default_rng(0).random(8192)
    rows, prev = [], None
    t_end = time.perf_counter() + seconds
    while time.perf_counter() < t_end and not stop():
        core0, steal0, w0 = _reading(tid)
        c0, t0 = time.thread_time(), time.perf_counter()
        for _ in range(4):
            np.sort(work)
        t1, c1 = time.perf_counter(), time.thread_time()
        core1, steal1, w1 = _reading(tid)
        if prev is not None:  # the previous piece's steal up to now (this piece's start reading)
            pc, ps0 = prev
            rows[-1][6] = steal0[pc] - ps0[pc] if pc < len(steal0) else np.nan
        same = core0 == core1 and core0 < len(steal1)
        rows.append([t0, t1, c1 - c0, w1 - w0, core1, steal1[core0] - steal0[core0] if same else np.nan, np.nan])
        prev = (core0, steal0) if same else None
        time.sleep(interval)
    return np.array(rows, float).reshape(-1, 7)


def summary(rows: np.ndarray) -> list[str]:
    """Printed lines: own CPU per piece, the pieces charged many times it, and whether steal was reported for them."""
    if len(rows) == 0:
        return ["no pieces"]
    wall, cpu, wait, steal, steal_next = rows[:, 1] - rows[:, 0], rows[:, 2], rows[:, 3], rows[:, 5], rows[:, 6]
    med = float(np.median(cpu))
    charged = cpu > CHARGED_FACTOR * med
    seen = np.nan_to_num(np.fmax(steal, steal_next)) > 0
    out = [f"{len(rows)} pieces; own CPU per piece median {1e3 * med:.3f} ms, "
           f"p99 {1e3 * np.percentile(cpu, 99):.2f} ms, max {1e3 * cpu.max():.1f} ms",
           f"wall in pieces {wall.sum():.2f} s, own CPU {cpu.sum():.2f} s, run-queue wait {wait.sum():.2f} s; "
           f"steal reported on their cores during them {np.nansum(steal):.2f} s (10-ms steps)",
           f"pieces charged > {CHARGED_FACTOR:g}x the median own CPU: {int(charged.sum())} "
           f"({1e3 * float(np.sum(cpu[charged] - med)):.0f} ms beyond the median); with steal reported on their core "
           f"by the next piece: {int((charged & seen).sum())}, without: {int((charged & ~seen).sum())}"]
    top = np.argsort(-cpu)[:8]
    out.append("largest: " + ", ".join(f"{1e3 * cpu[i]:.1f} ms (steal {1e3 * np.nan_to_num(steal[i]):.0f}/"
                                       f"{1e3 * np.nan_to_num(steal_next[i]):.0f})" for i in top))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--interval", type=float, default=0.01, help="sleep between pieces (s)")
    ap.add_argument("--out", default=None, help="save the rows to this .npy file")
    args = ap.parse_args()
    if args.seconds <= 0 or args.interval < 0:
        sys.exit(f"--seconds must be > 0 and --interval >= 0 (got {args.seconds}, {args.interval})")
    stopped = []
    signal.signal(signal.SIGTERM, lambda *_a: stopped.append(1))
    from _common import blas_kernel

    load0 = os.getloadavg()[0]
    try:
        rows = probe(args.seconds, args.interval, stop=lambda: bool(stopped))
    except KeyboardInterrupt:
        rows = np.zeros((0, 7))
    if args.out:
        np.save(args.out, rows)
    print(f"steal probe: fixed work every {1e3 * args.interval:g} ms, load average {load0:.1f} -> "
          f"{os.getloadavg()[0]:.1f}; BLAS {blas_kernel()}")
    for line in summary(rows):
        print("   " + line)


if __name__ == "__main__":
    main()

"""A benchmark run as a set of measurements: timing, peak memory, the BLAS kernel, machine load,
cold and warm figures, and the JSON record of the run that is appended to ``history.jsonl``.

One concept: a **measurement** is a named quantity taken ``n`` times. Timing a callable
(:meth:`Harness.measure`) times its first call apart from the repeats that follow: the first
call is **cold** when nothing earlier in the process ran the same path (the caller says so;
a fresh process per call is the sure way, :meth:`Harness.children`), the repeats are
**warm**. Each measurement keeps min and median, the peak traced memory of the first call
(tracemalloc), the process's peak resident memory (VmHWM) after it and the one-minute load
average. Figures taken some other way (a child process's JSON, a rate, a ratio) enter with
:meth:`Harness.figure`.

The run itself records the BLAS libraries with their kernel and the OPENBLAS_* setting that
picks it, the load average at start and end, the share of CPU time stolen by the hypervisor
over the run (``/proc/stat``, where it shows steal), the git commit and the machine.
:meth:`Harness.finish` prints that, writes the record to ``--json FILE`` when asked and
appends it as one line to ``benchmarks/history.jsonl`` (not with ``--no-history`` or
``LIPSPACE_BENCH_NO_HISTORY=1``); ``tools/benchmark_table.py`` makes the README's table
from that file.
"""
from __future__ import annotations

import datetime
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
import tracemalloc
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from _common import blas_record, blas_text, peak_rss_mb, run_child_json

HERE = Path(__file__).resolve().parent
HISTORY = HERE / "history.jsonl"
NO_HISTORY_ENV = "LIPSPACE_BENCH_NO_HISTORY"
CODE = ("engine", "app", "benchmarks/*.py")  # what a run imports: changes there mark its record

__all__ = ["Harness", "Measurement", "HISTORY", "machine_record", "git_commit",
           "cpu_times", "steal_share", "append_history", "read_history"]


@dataclass
class Measurement:
    """One named quantity taken ``len(values)`` times.

    ``values`` are in ``unit``; for timings (unit ``"s"``) ``values[0]`` is the first call
    and ``cold`` says whether it was the first in a fresh process. ``warm`` are the values
    after the first (empty for a single call); ``min`` / ``median`` are over ``warm`` when
    there are any, over all values otherwise.
    """

    name: str
    values: list
    unit: str = "s"
    cold: bool | None = None
    first_is_separate: bool = True
    peak_traced_mib: float | None = None
    peak_rss_mib: float | None = None
    cpu_s: list | None = None
    load1: float | None = None
    headline: bool = False
    note: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def warm(self) -> list:
        return self.values[1:] if self.first_is_separate and len(self.values) > 1 else []

    @property
    def _over(self) -> list:
        return self.warm or self.values

    @property
    def min(self) -> float:
        return min(self._over)

    @property
    def median(self) -> float:
        return float(statistics.median(self._over))

    @property
    def first(self) -> float:
        return self.values[0]

    def as_dict(self) -> dict:
        d = {k: v for k, v in asdict(self).items()
             if v not in (None, "", {}) and k not in ("name", "first_is_separate")}
        d.update(min=self.min, median=self.median, n=len(self.values), n_warm=len(self.warm))
        if self.first_is_separate:
            d["first"] = self.first
        return d

    def line(self) -> str:
        """One printed line: min / median (of n), the first call, memory, load."""
        f = _fmt(self.unit)
        if len(self.values) == 1:
            s = f"{self.name:<46} {f(self.first)}" + (" (cold)" if self.cold else "")
        else:
            over = f"{len(self.warm)} warm" if self.warm else f"{len(self.values)}"
            s = f"{self.name:<46} min {f(self.min)}   median {f(self.median)} (of {over})"
            if self.warm:
                s += f"   first {f(self.first)}" + (" (cold)" if self.cold else "")
        if self.cpu_s:
            s += f"   CPU median {f(statistics.median(self.cpu_s))}"
        if self.peak_traced_mib is not None:
            s += f"   peak traced {self.peak_traced_mib:7.1f} MiB"
        if self.peak_rss_mib is not None:
            s += f"   max RSS {self.peak_rss_mib:6.0f} MiB"
        if self.load1 is not None:
            s += f"   [load {self.load1:.1f}]"
        return s + (f"   {self.note}" if self.note else "")


def _fmt(unit: str):
    if unit == "s":
        return lambda v: f"{1000 * v:9.1f} ms" if abs(v) < 1 else f"{v:9.2f} s "
    return lambda v: f"{v:9.4g} {unit}"


def cpu_times() -> tuple[float, float] | None:
    """(all CPU time, stolen time) in USER_HZ ticks from the aggregate ``cpu`` line of
    ``/proc/stat``; None where there is no such file."""
    try:
        with open("/proc/stat") as fh:
            f = fh.readline().split()
    except OSError:
        return None
    if not f or f[0] != "cpu":
        return None
    ticks = [int(x) for x in f[1:9]]  # user nice system idle iowait irq softirq steal
    return float(sum(ticks)), float(ticks[7]) if len(ticks) > 7 else 0.0


def steal_share(start, end) -> float | None:
    """Share of all CPU time stolen by the hypervisor between two :func:`cpu_times` readings."""
    if start is None or end is None or end[0] <= start[0]:
        return None
    return (end[1] - start[1]) / (end[0] - start[0])


def machine_record() -> dict:
    """The machine a run took its figures on (no host name)."""
    model = ""
    try:
        with open("/proc/cpuinfo") as fh:
            model = next((ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")), "")
    except OSError:
        pass
    return {"arch": platform.machine(), "cpu": model, "cpus": os.cpu_count(), "system": platform.system(),
            "python": platform.python_version(), "numpy": np.__version__}


def git_commit(repo: Path = HERE.parent) -> dict:
    """``{"commit": short hash, "dirty": bool}`` of the checkout; ``dirty`` when the code a run
    imports (``engine/``, ``app/``, ``benchmarks/``) has uncommitted changes (empty strings
    outside git)."""
    def run(*a):
        r = subprocess.run(["git", "-C", str(repo), *a], capture_output=True, text=True)
        return r.stdout.strip() if r.returncode == 0 else ""

    sha = run("rev-parse", "--short", "HEAD")
    dirty = bool(run("status", "--porcelain", "--untracked-files=no", "--", *CODE)) if sha else False
    return {"commit": sha, "dirty": dirty}


def append_history(record: dict, path: Path = HISTORY) -> None:
    """Append ``record`` as one JSON line to ``path`` (one ``write`` of one line, so runs that
    finish together do not interleave)."""
    line = json.dumps(record, allow_nan=False, default=_jsonable) + "\n"  # figures keep their order
    with open(path, "a", encoding="utf-8") as fh:
        fh.write(line)


def read_history(path: Path = HISTORY) -> list[dict]:
    """Every record of a history file, in the order they were appended.

    Raises
    ------
    ValueError
        When a line is not a JSON object: the file and line number.
    """
    out = []
    with open(path, encoding="utf-8") as fh:
        for k, line in enumerate(fh, 1):
            if not line.strip():
                continue
            try:
                rec = json.loads(line)
            except json.JSONDecodeError as e:
                raise ValueError(f"{path}:{k}: not a JSON record ({e.msg}); expected one object per line") from e
            if not isinstance(rec, dict) or "benchmark" not in rec:
                raise ValueError(f"{path}:{k}: expected a JSON object with a 'benchmark' field")
            out.append(rec)
    return out


def _jsonable(v):
    if hasattr(v, "item"):  # numpy scalars
        return v.item()
    if isinstance(v, Path):
        return str(v)
    return repr(v)


def _clean(v):
    """NaN and infinities become None so the record is strict JSON."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    return v


class Harness:
    """One benchmark run: its measurements and the record of the conditions they were taken under.

    Parameters
    ----------
    name : str
        The benchmark (its script name without ``.py``).
    args : argparse.Namespace, optional
        The parsed command line: its values go into the record as ``params``, and its
        ``json`` / ``no_history`` (from :meth:`add_arguments`) choose where the record goes.
    history : path, optional
        The history file (default ``benchmarks/history.jsonl``).
    quiet : bool
        Print nothing (the record is still made).
    """

    def __init__(self, name: str, args=None, *, history: Path | None = None, quiet: bool = False):
        self.name = name
        self.params = {k: v for k, v in sorted(vars(args).items()) if k not in ("json", "no_history")} if args else {}
        self.json_path = getattr(args, "json", None)
        self.history = None if (getattr(args, "no_history", False) or os.environ.get(NO_HISTORY_ENV)) \
            else (history or HISTORY)
        self.quiet = quiet
        self.measurements: list[Measurement] = []
        self.facts: dict = {}
        self._t0 = time.perf_counter()
        self._cpu0 = cpu_times()
        self._load0 = os.getloadavg()
        self._loads = [self._load0[0]]
        self.blas = blas_record()
        self._say(f"{name}: BLAS {blas_text(self.blas)}; load {self._load0[0]:.1f}")

    # -- command line -------------------------------------------------------------------------
    @staticmethod
    def add_arguments(ap) -> None:
        """``--json FILE`` (write the run's record there) and ``--no-history`` (do not append it
        to ``benchmarks/history.jsonl``)."""
        g = ap.add_argument_group("result record")
        g.add_argument("--json", metavar="FILE", help="also write this run's JSON record to FILE")
        g.add_argument("--no-history", action="store_true",
                       help=f"do not append the record to {HISTORY.relative_to(HERE.parent)}")

    # -- measuring ------------------------------------------------------------------------------
    def _say(self, text: str) -> None:
        if not self.quiet:
            print(text, flush=True)

    def _load(self) -> float:
        la = os.getloadavg()[0]
        self._loads.append(la)
        return la

    def measure(self, name: str, fn, *, repeat: int = 0, cold: bool | None = None, trace: bool = True,
                cpu: bool = False, headline: bool = False, note: str = "", **extra):
        """Time ``fn()``: its first call, then ``repeat`` more calls (warm).

        Parameters
        ----------
        name : str
            What is timed.
        fn : callable
            Called ``1 + repeat`` times with no arguments.
        repeat : int
            Warm calls after the first; 0 times a single call.
        cold : bool, optional
            Whether the first call is the first of its path in a fresh process (the caller
            knows; ``None``: not stated).
        trace : bool
            Peak traced memory (tracemalloc) of the first call; it slows allocation-heavy
            code a little, so the first call's time is then an upper bound.
        cpu : bool
            Also the process CPU time of each call (all threads).
        headline : bool
            Show this figure in the README table.

        Returns
        -------
        out : object
            What the last call returned.
        m : Measurement
        """
        times, cpus, peak, out = [], [], None, None
        for k in range(1 + repeat):
            if k == 0 and trace:
                tracemalloc.start()
                tracemalloc.reset_peak()
            t, c = time.perf_counter(), time.process_time()
            out = fn()
            times.append(time.perf_counter() - t)
            cpus.append(time.process_time() - c)
            if k == 0 and trace:
                peak = tracemalloc.get_traced_memory()[1] / 2**20
                tracemalloc.stop()
        m = Measurement(name, times, "s", cold=cold, peak_traced_mib=peak, peak_rss_mib=peak_rss_mb(),
                        cpu_s=cpus if cpu else None, load1=self._load(), headline=headline, note=note, extra=extra)
        return out, self.add(m)

    def figure(self, name: str, values, unit: str = "s", *, cold: bool | None = None, first_is_separate: bool = False,
               peak_rss_mib: float | None = None, peak_traced_mib: float | None = None, headline: bool = False,
               note: str = "", show: bool = True, **extra) -> Measurement:
        """A quantity measured some other way (a child's JSON, a rate, a ratio): one value or a list.

        By default every value is one repeat (``first_is_separate=False``); pass ``True`` when
        ``values[0]`` is a first call to keep apart from the warm ones. ``show=False`` keeps
        the figure without printing its line (for a benchmark that prints its own table).
        """
        vals = [float(v) for v in (values if isinstance(values, (list, tuple)) else [values])]
        if not vals:
            raise ValueError(f"figure {name!r}: no values; expected one number or a non-empty list")
        return self.add(Measurement(name, vals, unit, cold=cold, first_is_separate=first_is_separate,
                                    peak_traced_mib=peak_traced_mib, peak_rss_mib=peak_rss_mib, load1=self._load(),
                                    headline=headline, note=note, extra=extra), show=show)

    def children(self, name: str, cmd, *, repeat: int = 1, key: str = "wall_s", headline: bool = False,
                 rss_key: str = "max_rss_MiB", **kwargs):
        """Run ``cmd`` (a child printing a JSON object on its last line) ``repeat`` times, each a
        fresh process, and record ``child[key]`` of each as one cold figure.

        Returns the list of the children's JSON objects.
        """
        rows = [run_child_json(cmd, **kwargs) for _ in range(repeat)]
        rss = [r[rss_key] for r in rows if isinstance(r, dict) and r.get(rss_key) is not None]
        self.figure(name, [r[key] for r in rows], "s", cold=True, peak_rss_mib=max(rss) if rss else None,
                    headline=headline)
        return rows

    def add(self, m: Measurement, show: bool = True) -> Measurement:
        """Keep ``m`` and print its line (unless ``show`` is false)."""
        self.measurements.append(m)
        if show:
            self._say(m.line())
        return m

    def fact(self, **facts) -> None:
        """Conditions or results that are not measurements (sizes, counts, a checksum)."""
        self.facts.update(facts)

    # -- the record -----------------------------------------------------------------------------
    def record(self) -> dict:
        """The JSON record of the run so far."""
        cpu1 = cpu_times()
        load1 = os.getloadavg()
        self._loads.append(load1[0])
        steal = steal_share(self._cpu0, cpu1)
        names = [m.name for m in self.measurements]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"{self.name}: figures named twice: {sorted(dup)}; give each measurement its own name")
        rec = {
            "benchmark": self.name,
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            **git_commit(),
            "argv": sys.argv[1:],
            "params": self.params,
            "machine": machine_record(),
            "blas": blas_record(),  # every library loaded by the end of the run
            "load": {"start": list(self._load0), "end": list(load1), "min1": min(self._loads),
                     "max1": max(self._loads), "steal_share": steal},
            "wall_s": time.perf_counter() - self._t0,
            "peak_rss_mib": peak_rss_mb(),
            "figures": {m.name: m.as_dict() for m in self.measurements},
            "headline": [m.name for m in self.measurements if m.headline],
            "facts": self.facts,
        }
        return _clean(json.loads(json.dumps(rec, default=_jsonable)))

    def finish(self) -> dict:
        """Print the run's conditions, write ``--json FILE`` and append the record to the history."""
        rec = self.record()
        ld = rec["load"]
        steal = "" if ld["steal_share"] is None else f"; steal {100 * ld['steal_share']:.1f}% of CPU time"
        self._say(f"({self.name}: {rec['wall_s']:.1f} s; peak RSS {rec['peak_rss_mib'] or float('nan'):.0f} MiB; "
                  f"load {ld['min1']:.1f}-{ld['max1']:.1f}{steal}; BLAS {blas_text(rec['blas'])}; "
                  f"commit {rec['commit']}{' +changes' if rec['dirty'] else ''})")
        if self.json_path:
            Path(self.json_path).write_text(json.dumps(rec, indent=1) + "\n")
        if self.history is not None:
            append_history(rec, self.history)
            self._say(f"(record appended to {self.history})")
        return rec

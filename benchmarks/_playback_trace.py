"""Time stamps of every playback frame's stages, and why a late frame was late (bench_gui_playback.py).

A :class:`PlaybackTrace` attached to the explorer's lip view records, on one clock
(``time.perf_counter``, the monotonic clock the playback clock runs on):

* each tick of the playback timer: when ``PlaybackClock.frame`` was called, the frame it
  chose, the look-ahead it used, and when that tick had been planned (the deadline the
  previous tick set the single-shot timer to);
* the lip view's VTK render (render window Start/End events) and its ``frameSwapped``
  (the frame is on screen);
* the manifold view's renders (the other view sharing the GUI thread);
* Python's garbage collections (``gc.callbacks``: start, stop, generation);
* the GUI thread's CPU time and run-queue wait (``/proc/thread-self/schedstat``: time it
  was runnable but another process held the core) at each tick and each swap;
* at each tick and each swap, what happened on the machine outside the process
  (:func:`read_counters`): the core the GUI thread is on, its exact CPU clock
  (``time.thread_time``), its user / system ticks and page faults
  (``/proc/thread-self/stat``), each core's **steal** (time the hypervisor ran something
  else on that virtual core, ``/proc/stat``) and interrupt ticks, and the kernel's page
  migration, compaction and huge-page counters (``/proc/vmstat``).

:func:`frame_table` turns the records into one row per distinct frame shown, and
:func:`late_causes` says, for each frame more than one period late at its swap, which of
the recorded causes took the most of its delay (pure numpy: tested without Qt).
"""
from __future__ import annotations

import gc
import os
import threading
import time
from typing import NamedTuple

import numpy as np

__all__ = ["PlaybackTrace", "frame_table", "late_causes", "long_frames", "CAUSES", "read_schedstat",
           "read_counters", "Counters", "LONG_FRAME_CPU_S"]

#: causes of a late frame, in the order they are reported
CAUSES = ("gc", "preempted", "steal", "other view", "long render", "long compose", "queued")

#: a frame whose GUI thread used more CPU than this between its choice and its swap is a "long frame"
#: (the per-frame median is about 6 ms)
LONG_FRAME_CPU_S = 0.040

#: /proc/vmstat counters read with each tick and swap (page migration, compaction, huge pages)
VMSTAT_KEYS = ("pgmigrate_success", "compact_stall", "thp_fault_alloc", "thp_collapse_alloc", "thp_split_pmd")


class Counters(NamedTuple):
    """One reading of the GUI thread's and the machine's counters (:func:`read_counters`).

    ``processor`` is the core the thread last ran on; ``thread_cpu`` its CPU clock (s,
    exact); ``utime`` / ``stime`` its user / system CPU in clock ticks' seconds (10 ms
    steps); ``minflt`` / ``majflt`` its page faults; ``steal`` and ``irq`` per core (s,
    10-ms steps of ``/proc/stat``: hypervisor steal, and interrupt + softirq ticks);
    ``vm`` the :data:`VMSTAT_KEYS` counters.
    """

    processor: int
    thread_cpu: float
    utime: float
    stime: float
    minflt: int
    majflt: int
    steal: tuple
    irq: tuple
    vm: tuple


def parse_proc_stat(text: str, hz: float = 100.0) -> tuple[tuple, tuple]:
    """(steal per core, irq + softirq per core), seconds, from the text of ``/proc/stat``.

    Each ``cpuN`` line is ``user nice system idle iowait irq softirq steal ...`` in
    ``1/hz`` s (USER_HZ); core N's values are at index N.
    """
    steal, irq = {}, {}
    for line in text.splitlines():
        if line.startswith("cpu") and len(line) > 3 and line[3].isdigit():
            f = line.split()
            n = int(f[0][3:])
            irq[n] = (int(f[6]) + int(f[7])) / hz
            steal[n] = int(f[8]) / hz
    n = max(steal) + 1 if steal else 0
    return tuple(steal.get(i, 0.0) for i in range(n)), tuple(irq.get(i, 0.0) for i in range(n))


def parse_task_stat(text: str, hz: float = 100.0) -> tuple[int, float, float, int, int]:
    """(processor, utime s, stime s, minflt, majflt) from the text of ``/proc/<pid>/task/<tid>/stat``.

    Fields after the parenthesised command name: state is field 3, minflt 10, majflt 12,
    utime 14, stime 15, processor 39 (proc(5) numbering).
    """
    rest = text[text.rindex(")") + 2:].split()
    return int(rest[36]), int(rest[11]) / hz, int(rest[12]) / hz, int(rest[7]), int(rest[9])


def read_counters() -> Counters | None:
    """The calling thread's and the machine's counters now (None where /proc cannot be read)."""
    hz = float(os.sysconf("SC_CLK_TCK")) if hasattr(os, "sysconf") else 100.0
    try:
        cpu = time.thread_time()
        with open("/proc/thread-self/stat") as fh:
            proc, ut, st, mf, jf = parse_task_stat(fh.read(), hz)
        with open("/proc/stat") as fh:
            steal, irq = parse_proc_stat(fh.read(), hz)
        vm = dict.fromkeys(VMSTAT_KEYS, 0)
        with open("/proc/vmstat") as fh:
            for line in fh:
                key, _, val = line.partition(" ")
                if key in vm:
                    vm[key] = int(val)
    except (OSError, ValueError, IndexError):
        return None
    return Counters(proc, cpu, ut, st, mf, jf, steal, irq, tuple(vm[k] for k in VMSTAT_KEYS))


def read_schedstat(path: str = "/proc/thread-self/schedstat") -> tuple[float, float]:
    """(CPU seconds, run-queue wait seconds) of the calling thread; (nan, nan) where there is no such file."""
    try:
        with open(path) as fh:
            cpu, wait, _ = fh.read().split()
        return int(cpu) * 1e-9, int(wait) * 1e-9
    except (OSError, ValueError):
        return float("nan"), float("nan")


def x_server_pid() -> int | None:
    """The pid of the Xvfb serving ``$DISPLAY`` (None when there is none or it cannot be read)."""
    import os

    display = os.environ.get("DISPLAY", "")
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as fh:
                args = fh.read().split(b"\0")
        except OSError:
            continue
        if args and args[0].endswith(b"Xvfb") and display.encode() in args:
            return int(pid)
    return None


class HelperWaits:
    """Run-queue wait (s) of the process's other threads (the software rasteriser's) and the X server."""

    def __init__(self):
        import os

        me = threading.get_native_id()
        self.paths = [f"/proc/self/task/{t}/schedstat" for t in os.listdir("/proc/self/task") if int(t) != me]
        pid = x_server_pid()
        self.x_paths = ([] if pid is None else
                        [f"/proc/{pid}/task/{t}/schedstat" for t in os.listdir(f"/proc/{pid}/task")])

    def __call__(self) -> tuple[float, float]:
        """(largest wait of one rasteriser/helper thread, X server's total wait), cumulative seconds."""
        w = [read_schedstat(p)[1] for p in self.paths]
        x = [read_schedstat(p)[1] for p in self.x_paths]
        return max([v for v in w if v == v] or [0.0]), float(np.nansum(x)) if x else 0.0


class PlaybackTrace:
    """Record the stages of the lip view's playback frames (see the module docstring).

    ``attach(win)`` before pressing Play, ``detach()`` after; the lists hold
    ``time.perf_counter()`` stamps.
    """

    def __init__(self):
        # (t, frame chosen or None, look-ahead s, planned t or nan, thread cpu, run wait, helper wait,
        #  X server wait, Counters or None)
        self.ticks = []
        self.render_start, self.render_end = [], []
        self.swaps = []  # (t, thread cpu, run wait, helper wait, X server wait, Counters or None)
        self.m_start, self.m_end = [], []
        self.gcs = []  # (t start, t stop, generation)
        self._gc_t0 = None
        self._planned = float("nan")
        self._undo = []
        self.helpers = None
        self.clock_start = None  # (monotonic time, frame) the playback clock started at

    # ----------------------------------------------------------------- hooks
    def _on_gc(self, phase, info):
        if threading.current_thread() is not threading.main_thread():
            return
        if phase == "start":
            self._gc_t0 = time.perf_counter()
        elif self._gc_t0 is not None:
            self.gcs.append((self._gc_t0, time.perf_counter(), int(info.get("generation", -1))))
            self._gc_t0 = None

    def attach(self, win) -> None:
        lv = win.lip_view
        self.helpers = HelperWaits()
        try:
            from app.models.playback import PlaybackClock
        except ImportError:  # trees without a playback clock: no per-tick records
            PlaybackClock = None
        if PlaybackClock is not None:
            original = PlaybackClock.frame
            trace = self

            def frame(clock):
                t = time.perf_counter()
                cpu, wait = read_schedstat()
                counters = read_counters()
                k = original(clock)
                ahead = getattr(clock, "look_ahead_s", clock.latency_s)  # older code: the latency alone
                trace.ticks.append((t, k, ahead, trace._planned, cpu, wait, *trace.helpers(), counters))
                trace.clock_start = (clock.t0, clock.start_frame)
                trace._planned = float("nan")
                return k

            PlaybackClock.frame = frame
            self._undo.append(lambda: setattr(PlaybackClock, "frame", original))
        timer = getattr(lv, "timer", None)
        if timer is not None:
            start = timer.start

            def timed_start(ms=None):
                if ms is None:
                    return start()
                self._planned = time.perf_counter() + ms / 1000.0
                return start(ms)

            timer.start = timed_start
            self._undo.append(lambda: delattr(timer, "start"))
        rw, mrw = lv.plotter.render_window, win.manifold_view.plotter.render_window
        for window, event, store in ((rw, "StartEvent", self.render_start), (rw, "EndEvent", self.render_end),
                                     (mrw, "StartEvent", self.m_start), (mrw, "EndEvent", self.m_end)):
            tag = window.AddObserver(event, lambda *_a, s=store: s.append(time.perf_counter()))
            self._undo.append(lambda w=window, t=tag: w.RemoveObserver(t))

        def on_swap():
            t = time.perf_counter()
            self.swaps.append((t, *read_schedstat(), *self.helpers(), read_counters()))

        lv.plotter.interactor.frameSwapped.connect(on_swap)
        self._undo.append(lambda: lv.plotter.interactor.frameSwapped.disconnect(on_swap))
        gc.callbacks.append(self._on_gc)
        self._undo.append(lambda: gc.callbacks.remove(self._on_gc))

    def detach(self) -> None:
        while self._undo:
            self._undo.pop()()


def _overlap(a0, a1, starts, stops) -> float:
    """Seconds of the intervals [starts_i, stops_i] inside [a0, a1]."""
    if len(starts) == 0:
        return 0.0
    s = np.clip(np.asarray(starts, float), a0, a1)
    e = np.clip(np.asarray(stops, float), a0, a1)
    return float(np.maximum(e - s, 0.0).sum())


def frame_table(ticks, render_start, render_end, swaps, m_start, m_end, gcs, *, t0, rate) -> dict:
    """One row per distinct frame first put on screen by a lip swap after ``t0``.

    Parameters
    ----------
    ticks : sequence of (t, k, lookahead_s, planned_t, cpu_s, wait_s[, helper_wait_s, x_wait_s[, counters]])
        Playback clock calls (``k`` None at the end); the GUI thread's cumulative CPU and
        run-queue wait then, optionally the largest cumulative wait of one helper thread
        (the rasteriser's) and the X server's, and a :class:`Counters` reading (or None).
    render_start, render_end : sequence of float
        The lip view's VTK render start and end times (paired in order).
    swaps : sequence of (t, cpu_s, wait_s[, helper_wait_s, x_wait_s[, counters]])
        The lip view's ``frameSwapped`` times with the same counters then.
    m_start, m_end : sequence of float
        The manifold view's render start and end times.
    gcs : sequence of (t_start, t_stop, generation)
    t0 : float
        When Play was pressed (media time 0 of the reference clock).
    rate : float
        Frames per second.

    Returns
    -------
    dict of ndarray of shape (n_shown,)
        ``frame``, ``swap`` (time), ``lag`` (frame periods behind the clock at the swap),
        ``chosen`` (time of the tick that first chose the frame), ``lookahead`` (s),
        ``timer_late`` (s the tick fired after its planned time; nan when unplanned),
        ``queue`` (chosen -> render start, s), ``render`` (s), ``compose`` (render end ->
        swap, s), ``other_view``, ``gc`` (s of manifold renders / collections between
        choice and swap), ``run_wait`` (s the GUI thread waited for a core between choice
        and swap), ``helper_wait`` (the same for the helper thread that waited most, plus
        the X server), ``cpu`` (s of GUI-thread CPU between choice and swap). From the
        :class:`Counters` readings (nan without them), between choice and swap:
        ``thread_cpu`` (the GUI thread's CPU clock, s), ``utime`` / ``stime`` (its user /
        system CPU, 10-ms steps), ``minflt``, ``steal`` (s of hypervisor steal on the
        core(s) the GUI thread was on at choice and at swap; 10-ms steps), ``steal_next`` (the
        same from the choice to the first tick after the swap: the kernel adds steal to
        ``/proc/stat`` at its next timer tick on that core, so steal near the swap may
        show only then), ``steal_all``
        (all cores), ``irq`` (interrupt ticks' s on those cores), ``migrated`` (1 when the
        two cores differ), ``core`` (the core at the swap) and ``vm_<key>`` for each of
        :data:`VMSTAT_KEYS` (machine-wide).
    """
    def pad(row, n):
        row = tuple(row)
        counters = row[n] if len(row) > n else None
        return row[:n] + (0.0,) * (n - len(row[:n])) + (counters,)

    rs = np.asarray(render_start, float)
    re = np.asarray(render_end, float)
    n_r = min(len(rs), len(re))
    rs, re = rs[:n_r], re[:n_r]
    tk = [pad(x, 8) for x in ticks if x[1] is not None]
    tk_t = np.array([x[0] for x in tk])
    first_tick = {}
    for x in tk:
        first_tick.setdefault(x[1], x)  # later ticks may choose a frame again while it is due
    first = {}
    for row in swaps:
        sw = row[0]
        if sw < t0:
            continue
        j = int(np.searchsorted(rs, sw)) - 1
        if j < 0:
            continue
        # the frame the lip meshes held at that render: the latest tick choosing before it
        i = int(np.searchsorted(tk_t, rs[j], side="right")) - 1
        if i < 0:
            continue
        k = tk[i][1]
        if k not in first:
            first[k] = (pad(row, 5), first_tick[k], rs[j], re[j])
    rows = sorted(first.items(), key=lambda kv: kv[1][0][0])
    out = {key: np.full(len(rows), np.nan) for key in
           ("frame", "swap", "lag", "chosen", "lookahead", "timer_late", "queue", "render", "compose",
            "other_view", "gc", "run_wait", "helper_wait", "cpu", "thread_cpu", "utime", "stime", "minflt",
            "steal", "steal_next", "steal_all", "irq", "migrated", "core") + tuple(f"vm_{k}" for k in VMSTAT_KEYS)}
    tk_n = [x for x in tk if x[8] is not None]
    tk_n_t = np.array([x[0] for x in tk_n])

    def steal_on(a, b, cores):
        n = min(len(a.steal), len(b.steal))
        return sum(b.steal[c] - a.steal[c] for c in cores if c < n)

    gs = [g[0] for g in gcs]
    ge = [g[1] for g in gcs]
    for i, (k, ((sw, cpu, wait, hw, xw, n1), tick, r0, r1)) in enumerate(rows):
        t, _, la, planned, c0, w0, hw0, xw0, n0 = tick
        out["frame"][i] = k
        out["swap"][i] = sw
        out["lag"][i] = (sw - t0) * rate - k
        out["chosen"][i] = t
        out["lookahead"][i] = la
        out["timer_late"][i] = t - planned if np.isfinite(planned) else np.nan
        out["queue"][i] = r0 - t
        out["render"][i] = r1 - r0
        out["compose"][i] = sw - r1
        out["other_view"][i] = _overlap(t, sw, m_start[:len(m_end)], m_end[:len(m_start)])
        out["gc"][i] = _overlap(t, sw, gs, ge)
        out["run_wait"][i] = wait - w0
        out["helper_wait"][i] = (hw - hw0) + (xw - xw0)
        out["cpu"][i] = cpu - c0
        if n0 is not None and n1 is not None:
            cores = sorted({n0.processor, n1.processor})
            out["thread_cpu"][i] = n1.thread_cpu - n0.thread_cpu
            out["utime"][i] = n1.utime - n0.utime
            out["stime"][i] = n1.stime - n0.stime
            out["minflt"][i] = n1.minflt - n0.minflt
            out["steal"][i] = steal_on(n0, n1, cores)
            j = int(np.searchsorted(tk_n_t, sw, side="right"))
            n2 = tk_n[j][8] if j < len(tk_n) else n1
            out["steal_next"][i] = steal_on(n0, n2, sorted(set(cores) | {n2.processor}))
            out["steal_all"][i] = sum(n1.steal) - sum(n0.steal)
            out["irq"][i] = sum(n1.irq[c] - n0.irq[c] for c in cores if c < min(len(n0.irq), len(n1.irq)))
            out["migrated"][i] = float(len(cores) > 1)
            out["core"][i] = n1.processor
            for j, key in enumerate(VMSTAT_KEYS):
                out[f"vm_{key}"][i] = n1.vm[j] - n0.vm[j]
    return out


def late_causes(table: dict, *, rate: float, late: float = 1.0) -> list[str]:
    """For each frame more than ``late`` periods late at its swap, the cause that took most of its delay.

    The delay of a frame is the time from its choice to its swap beyond the look-ahead
    it was chosen with. Candidate shares of it: ``gc`` (collections between choice and
    swap), ``preempted`` (the GUI thread, the helper thread that waited most and the X
    server runnable but waiting for a core: other processes held it), ``steal`` (the
    hypervisor ran something else on the GUI thread's core: its steal counter, in 10-ms
    steps, between choice and swap; absent readings count 0), ``other view``
    (the manifold view rendering in between), ``long render`` and ``long compose`` (the
    lip render, or compose + swap, beyond their medians over the run), ``queued`` (choice
    -> render start beyond its median, less the collections and other view's renders in
    it). The largest share names the cause.

    Parameters
    ----------
    table : dict
        From :func:`frame_table`.
    rate : float
        Frames per second.
    late : float
        Threshold in frame periods.

    Returns
    -------
    list of str
        One of :data:`CAUSES` per late frame, in the order shown.
    """
    lag = np.asarray(table["lag"], float)
    idx = np.flatnonzero(lag > late)
    if idx.size == 0:
        return []
    med = {key: float(np.nanmedian(table[key])) for key in ("queue", "render", "compose")}
    helper = np.nan_to_num(np.asarray(table.get("helper_wait", np.zeros(len(lag))), float))
    run_wait = np.nan_to_num(np.asarray(table["run_wait"], float))
    steal = np.nan_to_num(np.asarray(table.get("steal", np.zeros(len(lag))), float))
    causes = []
    for i in idx:
        gc_s = table["gc"][i]
        other = table["other_view"][i]
        share = {
            "gc": gc_s,
            "preempted": run_wait[i] + helper[i],
            "steal": steal[i],
            "other view": other,
            "long render": table["render"][i] - med["render"],
            "long compose": table["compose"][i] - med["compose"],
            "queued": table["queue"][i] - med["queue"] - gc_s - other,
        }
        causes.append(max(CAUSES, key=lambda c: (share[c], -CAUSES.index(c))))
    return causes


def long_frames(table: dict, *, threshold_s: float = LONG_FRAME_CPU_S) -> list[dict]:
    """The frames whose GUI thread used more than ``threshold_s`` of CPU between choice and swap.

    For each, what the counters say about where that CPU went: the thread's own CPU
    (its exact clock, ``thread_cpu``, or the schedstat ``cpu`` without it), its excess
    over the median frame's, the steal on its core in the same interval, and whether
    that steal is enough to explain the excess (``steal_explains``: steal >= excess
    minus one 10-ms step of the counter). Steal can show as a thread's own CPU: on the
    virtual machine measured (``CONFIG_PARAVIRT_TIME_ACCOUNTING=y``) a fixed piece of
    work was charged up to 100 times its CPU when steal hit its core. A long frame
    whose excess the steal does not cover was charged time the counter did not report
    as steal (the steal may also show one tick later: ``steal_next``).

    Parameters
    ----------
    table : dict
        From :func:`frame_table`.
    threshold_s : float
        CPU seconds between choice and swap above which a frame is long.

    Returns
    -------
    list of dict
        One per long frame, in the order shown, with ``index`` (row of the table),
        ``frame``, ``lag``, ``chosen`` (time), ``latency`` (choice -> swap, s), ``cpu``, ``excess``,
        ``utime``, ``stime``, ``steal``, ``steal_next``, ``steal_all``, ``irq``, ``run_wait``, ``minflt``,
        ``core``, ``migrated``, ``steal_explains``, ``steal_next_explains`` (the same with
        ``steal_next``) and the ``vm_*`` deltas (s and counts;
        nan where a reading is missing).
    """
    cpu = np.asarray(table["thread_cpu"], float)
    if not np.isfinite(cpu).any():
        cpu = np.asarray(table["cpu"], float)
    if not np.isfinite(cpu).any():
        return []
    median = float(np.nanmedian(cpu))
    out = []
    for i in np.flatnonzero(np.nan_to_num(cpu) > threshold_s):
        excess = cpu[i] - median
        steal = float(table["steal"][i])
        row = {"index": int(i), "frame": int(table["frame"][i]), "lag": float(table["lag"][i]),
               "chosen": float(table["chosen"][i]), "latency": float(table["swap"][i] - table["chosen"][i]),
               "cpu": float(cpu[i]), "excess": excess,
               "steal_explains": bool(np.isfinite(steal) and steal >= excess - 0.010),
               "steal_next_explains": bool(np.isfinite(table["steal_next"][i])
                                           and table["steal_next"][i] >= excess - 0.010)}
        for key in ("utime", "stime", "steal", "steal_next", "steal_all", "irq", "run_wait", "minflt", "core",
                    "migrated"):
            row[key] = float(table[key][i])
        for key in VMSTAT_KEYS:
            row[f"vm_{key}"] = float(table[f"vm_{key}"][i])
        out.append(row)
    return out

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
  was runnable but another process held the core) at each tick and each swap.

:func:`frame_table` turns the records into one row per distinct frame shown, and
:func:`late_causes` says, for each frame more than one period late at its swap, which of
the recorded causes took the most of its delay (pure numpy: tested without Qt).
"""
from __future__ import annotations

import gc
import threading
import time

import numpy as np

__all__ = ["PlaybackTrace", "frame_table", "late_causes", "CAUSES", "read_schedstat"]

#: causes of a late frame, in the order they are reported
CAUSES = ("gc", "preempted", "other view", "long render", "long compose", "queued")


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
        self.x_paths = [] if pid is None else [f"/proc/{pid}/task/{t}/schedstat" for t in os.listdir(f"/proc/{pid}/task")]

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
        self.ticks = []  # (t, frame chosen or None, look-ahead s, planned t or nan, thread cpu, run wait)
        self.render_start, self.render_end = [], []
        self.swaps = []  # (t, thread cpu, run wait)
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
            from app.playback import PlaybackClock
        except ImportError:  # trees without a playback clock: no per-tick records
            PlaybackClock = None
        if PlaybackClock is not None:
            original = PlaybackClock.frame
            trace = self

            def frame(clock):
                t = time.perf_counter()
                cpu, wait = read_schedstat()
                k = original(clock)
                trace.ticks.append((t, k, clock.latency_s, trace._planned, cpu, wait, *trace.helpers()))
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
            self.swaps.append((t, *read_schedstat(), *self.helpers()))

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
    ticks : sequence of (t, k, lookahead_s, planned_t, cpu_s, wait_s[, helper_wait_s, x_wait_s])
        Playback clock calls (``k`` None at the end); the GUI thread's cumulative CPU and
        run-queue wait then, optionally the largest cumulative wait of one helper thread
        (the rasteriser's) and the X server's.
    render_start, render_end : sequence of float
        The lip view's VTK render start and end times (paired in order).
    swaps : sequence of (t, cpu_s, wait_s[, helper_wait_s, x_wait_s])
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
        the X server), ``cpu`` (s of GUI-thread CPU between choice and swap).
    """
    def pad(row, n):
        return tuple(row) + (0.0,) * (n - len(row))

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
            "other_view", "gc", "run_wait", "helper_wait", "cpu")}
    gs = [g[0] for g in gcs]
    ge = [g[1] for g in gcs]
    for i, (k, ((sw, cpu, wait, hw, xw), tick, r0, r1)) in enumerate(rows):
        t, _, la, planned, c0, w0, hw0, xw0 = tick
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
    return out


def late_causes(table: dict, *, rate: float, late: float = 1.0) -> list[str]:
    """For each frame more than ``late`` periods late at its swap, the cause that took most of its delay.

    The delay of a frame is the time from its choice to its swap beyond the look-ahead
    it was chosen with. Candidate shares of it: ``gc`` (collections between choice and
    swap), ``preempted`` (the GUI thread, the helper thread that waited most and the X
    server runnable but waiting for a core: other processes held it), ``other view``
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
    causes = []
    for i in idx:
        gc_s = table["gc"][i]
        other = table["other_view"][i]
        share = {
            "gc": gc_s,
            "preempted": run_wait[i] + helper[i],
            "other view": other,
            "long render": table["render"][i] - med["render"],
            "long compose": table["compose"][i] - med["compose"],
            "queued": table["queue"][i] - med["queue"] - gc_s - other,
        }
        causes.append(max(CAUSES, key=lambda c: (share[c], -CAUSES.index(c))))
    return causes

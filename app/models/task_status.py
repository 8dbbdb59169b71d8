"""Where a long task is and how long it has left, from its progress reports (Qt-free).

A task reports ``(stage, done, total)`` as it goes. :class:`ProgressEstimate` keeps when each
report came and gives:

* the time left in the current stage, from the pace of its own counts (after its first count);
* the time left overall, where the task's stages are known (:data:`PLANS`: opening the
  synthetic talker, fitting a recording, a synthesis with its first validation): the stages
  still to come, weighted by their measured shares of the whole, at this machine's pace
  (the time the finished stages took over their shares). Shares were measured on the default
  synthetic talker; the pace of this run corrects them for the machine and the corpus size.

The status bar and every progress dialog show :meth:`ProgressEstimate.text`, refreshed each
second so that a long stage visibly lives even between its reports.
"""
from __future__ import annotations

import time

__all__ = ["stage_text", "ProgressEstimate", "PLANS", "format_seconds"]

#: known sequences of stages and each one's share of the whole (measured on the default talker, 2 cores)
PLANS = (
    # the synthetic talker built and fitted (File › Open synthetic talker, a first start): 172 s at 28,800 frames
    {"sentences": 0.011, "articulation": 0.068, "geometry": 0.070, "saving cache": 0.012, "speech audio": 0.086,
     "shape space": 0.065, "dynamic features": 0.095, "embedding": 0.391, "tangent frames": 0.077,
     "state graph": 0.075, "inverse map": 0.045, "preparing the views": 0.005},
    # a corpus or recording fitted (File › Open of a corpus, a .mat, a video): the same stages' shares
    {"shape space": 0.086, "dynamic features": 0.126, "embedding": 0.519, "tangent frames": 0.103,
     "state graph": 0.100, "inverse map": 0.059, "preparing the views": 0.007},
    # a cached manifold opened
    {"loading cached manifold": 0.6, "loading manifold": 0.6, "preparing the views": 0.4},
    # a synthesis with the corpus's first validation of the methods (39 s on the small talker), and text spoken
    {"synthesising": 0.01, "validation split": 0.03, "validation": 0.78, "validating every method": 0.15,
     "speaking the text": 0.03},
)


def format_seconds(s: float) -> str:
    """``"4 s"``, ``"1 min 20 s"``, ``"2 h 5 min"``."""
    s = max(0.0, float(s))
    if s < 60:
        return f"{s:.0f} s"
    if s < 3600:
        m, r = divmod(int(round(s)), 60)
        return f"{m} min {r} s" if r else f"{m} min"
    h, r = divmod(int(round(s)) // 60, 60)
    return f"{h} h {r} min" if r else f"{h} h"


def stage_text(stage: str, done: int, total: int, seconds: float, left: float | None = None) -> str:
    """The label for one progress report: ``"embedding 3/10 · 4 s · about 12 s left"``, or without a count."""
    count = f" {done}/{total}" if total > 1 and done < total else ""
    tail = "" if left is None else f" · about {format_seconds(left)} left"
    return f"{stage}{count} · {seconds:.0f} s{tail}"


class ProgressEstimate:
    """The time left of a task from its ``(stage, done, total)`` reports.

    Parameters
    ----------
    clock : callable() -> float
        Seconds (tests pass a fake).
    plans : sequence of dict
        Known stage sequences: stage -> share of the whole (:data:`PLANS`).
    """

    def __init__(self, *, clock=time.monotonic, plans=PLANS):
        self.clock = clock
        self.plans = plans
        self.started = clock()
        self.stages: list[list] = []  # [stage, first report time, latest (done, total), done at the first report]
        self.finished: dict = {}  # stage -> seconds it took

    # ------------------------------------------------------------------ reports
    def report(self, stage: str, done: int, total: int) -> None:
        now = self.clock()
        if not self.stages or self.stages[-1][0] != stage:
            if self.stages:
                prev = self.stages[-1]
                self.finished[prev[0]] = self.finished.get(prev[0], 0.0) + now - prev[1]
            self.stages.append([stage, now, (int(done), int(total)), int(done)])
            return
        cur = self.stages[-1]
        cur[2] = (int(done), int(total))

    @property
    def stage(self) -> str:
        return self.stages[-1][0] if self.stages else ""

    # ------------------------------------------------------------------ estimates
    def stage_left(self, now: float | None = None) -> float | None:
        """Seconds left in the current stage at the pace of its counts since its first report (None: no count
        made yet, or no total)."""
        if not self.stages:
            return None
        now = self.clock() if now is None else now
        _stage, t0, (done, total), d0 = self.stages[-1]
        if total <= 0 or done >= total or done <= d0:
            return None
        return (now - t0) / (done - d0) * (total - done)

    def _plan(self):
        seen = [s[0] for s in self.stages]
        for plan in self.plans:
            if seen and all(s in plan for s in seen[-3:]):
                return plan
        return None

    def left(self, now: float | None = None) -> float | None:
        """Seconds left of the whole task (None: not known yet)."""
        now = self.clock() if now is None else now
        plan = self._plan()
        here = self.stage_left(now)
        if plan is None:
            return here
        done_share = sum(plan[s] for s in self.finished if s in plan)
        spent = sum(d for s, d in self.finished.items() if s in plan)
        cur = self.stage
        order = list(plan)
        later = sum(plan[s] for s in order[order.index(cur) + 1:] if s not in self.finished) if cur in plan else 0.0
        if done_share <= 0 or spent <= 0:  # nothing finished yet: the current stage's own pace, if any
            if here is None or later == 0 or plan.get(cur, 0.0) <= 0:
                return here if later == 0 else None
            return here + later * (now - self.stages[-1][1] + here) / plan[cur]
        pace = spent / done_share  # seconds per unit share on this machine, this run
        if here is None:  # the current stage by its share, less what it has run
            here = max(plan.get(cur, 0.0) * pace - (now - self.stages[-1][1]), 0.0)
        return here + later * pace

    def text(self, now: float | None = None) -> str:
        """``"state graph 1/3 · 4 s · about 30 s left"`` (the time in the stage; what is left when known)."""
        if not self.stages:
            return "starting"
        now = self.clock() if now is None else now
        stage, t0, (done, total), _ = self.stages[-1]
        left = self.left(now)
        text = stage_text(stage, done, total, now - t0, left)
        return text if left is not None else text + " · estimating the time left"

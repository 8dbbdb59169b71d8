"""The time left of a long task, from its progress reports (Qt-free)."""
from __future__ import annotations

import pytest

from app.models.task_status import ProgressEstimate, format_seconds, stage_text


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def test_a_stage_with_counts_says_its_time_left_at_its_own_pace():
    clock = Clock()
    e = ProgressEstimate(clock=clock, plans=())
    e.report("validation", 0, 10)
    assert e.stage_left() is None and e.text().endswith("estimating the time left")  # no count made yet
    clock.t += 8.0
    e.report("validation", 2, 10)                        # 4 s a count
    assert e.stage_left() == pytest.approx(32.0)
    clock.t += 4.0                                        # no report for 4 s: the pace slows to 6 s a count
    assert e.text() == "validation 2/10 · 12 s · about 48 s left"


def test_the_whole_task_is_estimated_over_its_known_stages_at_this_runs_pace():
    clock = Clock()
    plan = {"a": 0.25, "b": 0.25, "c": 0.5}
    e = ProgressEstimate(clock=clock, plans=(plan,))
    e.report("a", 0, 1)
    assert e.left() is None                               # nothing finished: no pace yet
    clock.t += 10.0
    e.report("b", 0, 0)                                   # "a" took 10 s for a quarter: 40 s the whole
    assert e.left() == pytest.approx(10.0 + 20.0)         # b by its share, then c
    clock.t += 4.0
    assert e.left() == pytest.approx(6.0 + 20.0)          # b has run 4 of its 10 s
    e.report("c", 1, 4)
    clock.t += 6.0
    e.report("c", 2, 4)                                   # c's own pace: 6 s a count
    assert e.left() == pytest.approx(12.0)


def test_words_of_the_estimate():
    assert format_seconds(4.2) == "4 s" and format_seconds(80) == "1 min 20 s" and format_seconds(7500) == "2 h 5 min"
    assert stage_text("embedding", 3, 10, 4.2) == "embedding 3/10 · 4 s"
    assert stage_text("embedding", 3, 10, 4.2, 61) == "embedding 3/10 · 4 s · about 1 min 1 s left"

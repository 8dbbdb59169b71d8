"""A held-out evaluation's errors pooled per level of a metadata field, as the tables pool them."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from engine.evaluation.levels import MISSING_LEVEL, format_levels, per_level


def _sums(utt, frames, rmse_x, lve, method="manifold"):
    return {"protocol": "states", "method": method, "utterance": utt, "frames": frames, "frames_v": frames,
            "sq_x": frames * rmse_x ** 2, "sq_y": frames * 4.0, "lve_sum": frames * lve, "sq_v": frames * 1.0,
            "acc": 1.0, "acc_true": 1.0}


def test_levels_pool_frames_of_their_utterances():
    per = [_sums("a", 100, 1.0, 0.5), _sums("b", 300, 2.0, 1.5), _sums("c", 50, 3.0, 2.0), _sums("d", 10, 1.0, 1.0)]
    result = SimpleNamespace(_sums=per, rows=[{"protocol": "states", "method": "manifold"}])
    rows = per_level(result, {"a": "NE", "b": "NE", "c": "AN", "d": ""}, field="emotion")
    assert [r["level"] for r in rows] == ["AN", "NE", MISSING_LEVEL]
    ne = rows[1]
    assert ne["utterances"] == 2 and ne["frames"] == 400
    assert ne["rmse_x"] == pytest.approx(np.sqrt((100 * 1 + 300 * 4) / 400))
    assert ne["lve"] == pytest.approx((100 * 0.5 + 300 * 1.5) / 400)
    text = format_levels(rows, field="emotion")
    assert "AN (n=1)" in text and "NE (n=2)" in text and "levels with one held-out utterance (" in text

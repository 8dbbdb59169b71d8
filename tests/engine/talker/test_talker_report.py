"""engine.talker.report: scree counts, the trivial rule's classes and the realism report on the small talker."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from engine.talker.report import components_for, format_realism, rule_classes, talker_realism
from engine.talker.synthetic import gesture_phases


def test_components_for_counts_leading_components():
    assert components_for([0.5, 0.3, 0.15, 0.05]) == (2, 3, 4)
    assert components_for([5.0, 3.0, 1.5, 0.5], fractions=(0.5, 0.8)) == (1, 2)  # fractions of the sum
    with pytest.raises(ValueError, match="non-empty 1-D"):
        components_for([])


def test_rule_classes_read_the_same_convention_as_the_ground_truth():
    x = np.array([0, 1, 3, 4, 4.5, 4.0, 3.0, 2.9])
    bounds = np.array([[0, 8]])
    o, a = rule_classes(x, bounds)
    ph = gesture_phases(x, bounds)
    ok = ph >= 0
    ok[0] = False  # an utterance's first frame has no step into it: not scored by the report
    np.testing.assert_array_equal(o[ok], ph[ok] <= 1)
    np.testing.assert_array_equal(a[ok], np.isin(ph[ok], (0, 2)))


def test_realism_report_on_the_small_talker(small_manifold):
    r = talker_realism(small_manifold)
    assert r["x_recovered"][0] <= r["x_recovered"][1] <= r["x_recovered"][2] <= r["x_computed"]
    assert 0.8 < r["y3"] <= 1.0 and r["sign"] == 1.0
    # the report's ground truth is the talker's exact gesture phases: with the exact aperture as
    # "F^x_1" the rule reproduces them on every scored frame
    m = small_manifold

    class _Exact:  # the attributes talker_realism reads, with the exact aperture as F^x_1
        corpus_, shape_, embedding_, tangent_ = m.corpus_, m.shape_, m.embedding_, m.tangent_
        Fx_ = np.column_stack([m.corpus_.latent["aperture"], m.Fx_[:, 1:]])

    e = talker_realism(_Exact)
    assert e["rule"] == {"opening": 1.0, "accelerating": 1.0, "classes": 1.0}
    # on the noisy frames the rule and the method both find opening far above chance,
    # acceleration well below opening (capture noise in the second difference)
    for who in ("method", "rule"):
        assert r[who]["opening"] > 0.85 and 0.55 < r[who]["accelerating"] < r[who]["opening"]
    lines = format_realism(r)
    assert any("Delta F^x_1 rule" in ln for ln in lines) and any("Y1-3 hold" in ln for ln in lines)


def test_realism_report_needs_the_ground_truth(small_manifold):
    class _M:
        corpus_ = dataclasses.replace(small_manifold.corpus_, latent={})

    with pytest.raises(ValueError, match="no ground-truth 'aperture'"):
        talker_realism(_M)


def test_articulation_report_shares_activity_and_pairs():
    from engine.talker.lipmodel import CONTROL_NAMES, LipModel
    from engine.talker.report import articulation_report, format_articulation

    lip = LipModel("small")
    rng = np.random.default_rng(0)
    n = 3000
    C = np.zeros((n, len(CONTROL_NAMES)))
    j, r, p, c = (CONTROL_NAMES.index(k) for k in ("jaw", "round", "protrude", "corner"))
    C[:, j] = rng.random(n)                       # moves on every frame
    C[:, r] = 0.5 * rng.random(n)
    C[:, p] = 0.8 * C[:, r] + 0.02 * rng.standard_normal(n)   # protrusion follows rounding
    C[: n // 10, c] = 0.8                         # corners on a tenth of the frames
    out = articulation_report(lip, C)
    # the jaw is the largest source; shares are fractions of the noise-free variance
    assert max(out["share"], key=out["share"].get) == "jaw"
    assert all(0 <= v <= 1 for v in out["share"].values())
    assert out["share"]["closure"] == 0.0  # never moves: not deformed at all
    assert 0.95 < sum(out["share"].values()) < 1.05  # the surface is nearly linear in independent controls (0.99)
    assert out["active"]["jaw"] > 0.7 and out["active"]["corner"] == pytest.approx(0.1)
    assert out["active"]["closure"] == 0
    assert [(a, b) for a, b, _ in out["pairs"]] == [("round", "protrude")] and out["pairs"][0][2] > 0.95
    # three sources that move independently (jaw, round+protrude, corner): 99 % in at most three
    # components (measured 1, 1, 2: the jaw holds 95 %)
    assert out["components"][2] <= 3 and out["scree"][0] == pytest.approx(out["share"]["jaw"], abs=0.02)
    lines = format_articulation(out)
    assert "round-protrude" in lines[-1] and lines[1].split(": ")[1].startswith("jaw")
    with pytest.raises(ValueError, match="controls must have shape"):
        articulation_report(lip, C[:, :5])

"""Comparing conditions of the synthetic talker: a known difference is found where it is and not elsewhere,
and conditions that differ by chance only give nothing."""
import numpy as np
import pytest

from engine.comparison.compare import COLUMNS, ConditionComparison
from engine.comparison.statistics import bh_qvalues
from engine.progress import Cancelled

FAST = dict(n_permutations=999, n_bootstrap=200, random_state=0)


def _compare(conditions, levels, contrasts, **kw):
    cc, m = conditions
    return ConditionComparison(**FAST).fit(m, levels, by="condition", contrasts=contrasts,
                                           speakers=cc.fields["speaker"], pairs=cc.fields["text"], paired_by="text",
                                           **kw)


def _affected_members(conditions, result, level):
    """Per cluster: the share of its members in ``level`` that the effect moved."""
    cc, m = conditions
    pc, uidx = result.clusters_, m.corpus_.utterance_index
    out = {}
    for i, ph in enumerate(pc.phones_):
        mem = pc.members_[pc.member_offsets_[i]:pc.member_offsets_[i + 1]]
        mine = cc.fields["condition"][uidx[mem]] == level
        out[ph] = float(np.mean(cc.effect_mm[mem][mine] > 0.1)) if mine.any() else 0.0
    return out


def _true_speeds(conditions, level):
    """Mean |d aperture / dt| (mm/s) of the level's opening and closing frames, from the talker's true aperture."""
    cc, m = conditions
    c = m.corpus_
    v = np.gradient(c.latent["aperture"]) * c.rate
    mine = cc.fields["condition"][c.utterance_index] == level
    return np.abs(v[mine & (v > 0)]).mean(), np.abs(v[mine & (v < 0)]).mean()


def test_wider_bilabial_releases_are_found_there_and_not_elsewhere(conditions):
    cc, m = conditions
    r = _compare(conditions, cc.fields["condition"], [("a", "b")])
    assert r.designs_[0].kind == "within blocks" and r.designs_[0].testable
    affected = _affected_members(conditions, r, "b")
    clusters = sorted(r.table(family="cluster"), key=lambda row: row["p"])
    # there: the cluster that differs most is a bilabial whose every /b/-condition member the effect moved
    assert clusters[0]["target"] in ("p", "b") and affected[clusters[0]["target"]] == 1.0
    # not elsewhere: no cluster the effect never touched passes
    assert all(affected[row["target"]] > 0 for row in clusters if row["q"] < r.alpha)
    # the dynamics say the lips open faster, as the talker's true aperture does
    true_open_a, _ = _true_speeds(conditions, "a")
    true_open_b, _ = _true_speeds(conditions, "b")
    assert true_open_b > 1.05 * true_open_a
    row = next(x for x in r.table(family="dynamics") if x["target"] == "while opening")
    assert row["estimate"] > 1.05 and row["q"] < r.alpha and row["ci_low"] > 1.0
    # the states that differ most hold the frames the effect moved, many times their share of the corpus
    lab = m.states_.labels_
    moved = (cc.effect_mm > 0.1) & (cc.fields["condition"][m.corpus_.utterance_index] == "b")
    top = [int(x["target"]) for x in sorted(r.table(family="state"), key=lambda x: x["p"])[:10]]
    assert moved[np.isin(lab, top)].mean() > 3 * moved.mean()


def test_slower_closing_is_found_in_the_closing_speed(conditions):
    cc, m = conditions
    r = _compare(conditions, cc.fields["condition"], [("a", "c")])
    _, true_close_a = _true_speeds(conditions, "a")
    _, true_close_c = _true_speeds(conditions, "c")
    assert true_close_c < 0.95 * true_close_a
    rows = {(x["measure"], x["target"]): x for x in r.table(family="dynamics")}
    closing = rows[("opening speed", "while closing")]
    assert closing["estimate"] < 0.95 and closing["q"] < r.alpha and closing["ci_high"] < 1.0
    affected = _affected_members(conditions, r, "c")
    assert all(affected[x["target"]] > 0 for x in r.table(family="cluster") if x["q"] < r.alpha)


def test_a_random_split_of_one_condition_finds_nothing(conditions):
    cc, m = conditions
    rng = np.random.default_rng(0)
    levels = np.full(len(cc.fields["condition"]), "", dtype=object)
    for t in np.unique(cc.fields["text"]):
        idx = np.flatnonzero((cc.fields["condition"] == "a") & (cc.fields["text"] == t))
        rng.shuffle(idx)
        levels[idx[0]], levels[idx[1]] = "a1", "a2"
    r = _compare(conditions, levels, [("a1", "a2")])
    assert r.designs_[0].n_units == (10, 10)
    assert r.significant() == []
    p = np.array([x["p"] for x in r.rows_ if np.isfinite(x["p"])])
    assert np.mean(p < 0.05) < 0.1


def test_rows_arrays_and_joint_q_values(conditions):
    cc, m = conditions
    r = _compare(conditions, cc.fields["condition"], [("a", "b"), ("a", "c")])
    K = m.states_.centroids_.shape[0]
    assert r.enrichment_.shape == (2, K) and r.enrichment_q_.shape == (2, K)
    assert all(set(row) == set(COLUMNS) for row in r.rows_)
    assert {(x["level_a"], x["level_b"]) for x in r.rows_} == {("a", "b"), ("a", "c")}
    for fam in ("cluster", "dynamics", "state"):
        rows = r.table(family=fam)
        np.testing.assert_allclose([x["q"] for x in rows], bh_qvalues([x["p"] for x in rows]))
    dyn = r.table(family="dynamics", contrast=1)
    assert len(dyn) == 9 and all(x["n_utterances"] == 40 and x["n_speakers"] == 1 for x in dyn)
    assert all("within blocks" in x["design"] and "999 permutations" in x["design"] for x in dyn)
    share = r.occupancy_a_[0]
    assert np.nansum(share) == pytest.approx(100.0)


def test_one_utterance_per_level_describes_and_tests_nothing(conditions):
    cc, m = conditions
    levels = np.full(len(cc.fields["condition"]), "", dtype=object)
    levels[0], levels[2] = "x", "y"  # the same sentence, once in each
    r = _compare(conditions, levels, [("x", "y")])
    d = r.designs_[0]
    assert not d.testable and d.reason.startswith("one utterance per level")
    assert all(np.isnan(x["p"]) and np.isnan(x["q"]) and np.isnan(x["ci_low"]) for x in r.rows_)
    assert all(np.isfinite(x["estimate"]) for x in r.table(family="dynamics"))
    assert all("descriptive only" in x["design"] for x in r.rows_)


def test_bad_input_and_cancellation(conditions):
    cc, m = conditions
    with pytest.raises(ValueError, match="levels has 3 values for 60 utterances"):
        ConditionComparison().fit(m, ["a", "b", "c"])
    with pytest.raises(ValueError, match="n_permutations must be an integer >= 1, got 0"):
        ConditionComparison(n_permutations=0).fit(m, cc.fields["condition"], contrasts=[("a", "b")])

    def stop(stage, done, total):
        if stage == "permutations" and done:
            raise Cancelled("stop")

    with pytest.raises(Cancelled):
        _compare(conditions, cc.fields["condition"], [("a", "b")], progress=stop)

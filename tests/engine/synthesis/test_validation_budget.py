"""The validation's frame budget: unchanged within it, whole-utterance subsets and capped K above it."""

import math

import numpy as np
import pytest

import engine.synthesis.validation as val
from engine.graph.states import MAX_DEFAULT_STATES

#: a reduced grid keeps the test fast (the budget's logic does not depend on the grid's size)
GRID = {"state_dims": (3,), "sigmas": (0.0, 2.0), "neighbors": (20,), "frames_per_state": (30, 15, 8),
        "phones": False}


@pytest.fixture
def fits(monkeypatch):
    """Record the frames (F^y rows, utterance bounds) every validation state model is fitted on."""
    seen = []

    class Spy(val.StateModel):
        def fit(self, Fy, Fx, Fxv, bounds, phones=None):
            seen.append((np.asarray(Fy), np.asarray(bounds), self.n_states))
            return super().fit(Fy, Fx, Fxv, bounds, phones=phones)

    monkeypatch.setattr(val, "StateModel", Spy)
    return seen


def _fit_frames(m, s):
    held = set(s["val_ids"])
    return sum(u.n_frames for u in m.corpus_.utterances if u.id not in held)


def test_default_budget_is_the_state_graphs_cap_at_the_smallest_frames_per_state():
    assert val.default_fit_frames() == MAX_DEFAULT_STATES * min(val.FRAMES_PER_STATE_CANDIDATES)
    assert val.default_fit_frames((30, 15)) == MAX_DEFAULT_STATES * 15


def test_a_fit_split_within_the_budget_is_validated_as_without_a_bound(small_manifold, fits):
    m = small_manifold
    s = val.select_settings(m, **GRID)
    n_fit = _fit_frames(m, s)
    assert n_fit <= val.default_fit_frames()
    # the K candidates are one state per frames-per-state of the whole fit split, uncapped
    assert {r["frames_per_state"]: r["K"] for r in s["validation"].values()} == {
        f: round(n_fit / f) for f in GRID["frames_per_state"]}
    assert all(len(Fy) == n_fit for Fy, _, _ in fits)
    assert s["n_states"] == round(len(m.Fy_) / s["frames_per_state"])
    unbounded = val.select_settings(m, max_fit_frames=math.inf, **GRID)
    assert unbounded == s  # the same settings, diagnostics and note
    assert "budget" not in s["note"]


def test_over_the_budget_the_states_see_a_subset_of_whole_fit_utterances(small_manifold, fits, monkeypatch):
    m = small_manifold
    c = m.corpus_
    unbounded = val.select_settings(m, max_fit_frames=math.inf, **GRID)
    n_fit = _fit_frames(m, unbounded)
    fits.clear()
    budget = n_fit // 3
    cap = 40  # a lowered cap, so that the candidates reach it on the small corpus
    monkeypatch.setattr(val, "MAX_DEFAULT_STATES", cap)
    s = val.select_settings(m, max_fit_frames=budget, **GRID)
    assert fits
    starts = {int(u.start): u for u in c.utterances}
    held = set(s["val_ids"])
    for Fy, bounds, K in fits:
        assert len(Fy) <= budget and K <= cap
        used = []
        for a, b in bounds:  # every segment is one whole training utterance, none held out
            u = next(u for u in c.utterances if u.n_frames == b - a and np.array_equal(m.Fy_[u.start:u.stop], Fy[a:b]))
            assert u.id not in held and int(u.start) in starts
            used.append(u.id)
        assert len(set(used)) == len(used)
    # the candidates that reach the cap are merged into one
    Ks = [r["K"] for r in s["validation"].values()]
    assert len(Ks) == len(set(Ks)) and max(Ks) <= cap and len(Ks) < len(GRID["frames_per_state"])
    assert s["n_states"] <= cap
    # the validation utterances shrink in the same proportion, and the note says what was used
    n_val = sum(u.n_frames for u in c.utterances if u.id in held)
    assert len(held) == 2 or n_val <= budget * 0.2 / 0.8
    assert len(held) < len(unbounded["val_ids"]) and set(held) <= set(unbounded["val_ids"])
    assert f"scored on {len(held)} of the {len(unbounded['val_ids'])} validation utterances" in s["note"]
    assert f"over the {budget}-frame budget" in s["note"] and f"({len(fits[0][0])} frames)" in s["note"]
    assert f"K at most {cap}" in s["note"]
    # seeded: the same subset again
    fits_before = [len(Fy) for Fy, _, _ in fits]
    fits.clear()
    assert val.select_settings(m, max_fit_frames=budget, **GRID)["val_ids"] == s["val_ids"]
    assert [len(Fy) for Fy, _, _ in fits] == fits_before


@pytest.mark.parametrize("bad", [0, 1, -5, float("nan"), "many", True])
def test_a_bad_budget_names_value_limit_and_fix(small_manifold, bad):
    with pytest.raises(ValueError, match=r"max_fit_frames must be a number of frames >= 2 .*pass None"):
        val.select_settings(small_manifold, max_fit_frames=bad, **GRID)


def test_a_bad_val_fraction_names_its_range(small_manifold):
    with pytest.raises(ValueError, match=r"val_fraction must be in \(0, 1\), got 1.5"):
        val.select_settings(small_manifold, val_fraction=1.5, **GRID)


@pytest.fixture(scope="module")
def tiny_manifold(small_corpus):
    """Five utterances of the small talker: a split of a fifth would hold two."""
    from engine.manifold.model import Manifold

    return Manifold().fit(small_corpus.subset([u.id for u in small_corpus.utterances[:5]]))


def test_a_corpus_too_small_for_a_split_is_validated_by_leaving_each_utterance_out(tiny_manifold, fits):
    """Every training utterance is held out once from the states, the learnt paths and the inverse maps."""
    m = tiny_manifold
    utts = m.corpus_.utterances
    assert (len(utts) - 1) * m.corpus_.n_frames <= val.default_fit_frames()
    s = val.select_settings(m, **GRID)
    assert s["val_ids"] == [u.id for u in utts]
    assert "leave one out" in s["note"] and f"fewer than {val.MIN_SPLIT_UTTERANCES}" in s["note"]
    per_candidate = len(utts)
    assert len(fits) == per_candidate * len(GRID["frames_per_state"])
    for j, (Fy, bounds, K) in enumerate(fits):
        held = utts[j % per_candidate]  # the folds in corpus order, one per utterance
        kept = [u for u in utts if u is not held]
        assert [b - a for a, b in bounds] == [u.n_frames for u in kept]
        np.testing.assert_array_equal(Fy, np.concatenate([m.Fy_[u.start:u.stop] for u in kept]))
        assert K == max(2, round(len(Fy) / GRID["frames_per_state"][j // per_candidate]))
    # every method measured on all five, the manifold's weights fitted on the other folds
    assert set(s["method_validation"]) == {"states", "oracle"}
    assert s["best"]["states"] in s["method_validation"]["states"]
    assert s["blend"]["states"]["frames"] == sum(
        int(t.frames[-1]) + 1 - int(t.frames[0]) for t in (val.mid_frames(m, u.id) for u in utts))

"""The per-corpus method choice: the protocol a synthesis is in, the cache, the named default."""

import copy

import numpy as np
import pytest

from engine.phonetics.targets import Target, TargetSequence
from engine.synthesis import method_choice as mc

CHOICE = {"best": {"states": "manifold", "oracle": "manifold", "phones": "dominance"}, "blend": {},
          "method_validation": {"phones": {"manifold": {"rmse_x": 19.3, "lve": 2.8},
                                           "dominance": {"rmse_x": 13.9, "lve": 2.1},
                                           "linear": {"rmse_x": 17.9, "lve": 2.6}},
                                "states": {"manifold": {"rmse_x": 12.0, "lve": 1.9},
                                           "sv-hermite": {"rmse_x": 12.2, "lve": 1.9}}},
          "note": "chosen on 4 of 19 training utterances"}


def _seq(targets):
    return TargetSequence(tuple(targets), (), 30, 60.0)


def test_the_targets_decide_the_protocol():
    x, y = np.zeros(3), np.zeros(5)
    assert mc.target_protocol(_seq([Target(0, "m", 1, y, x), Target(9, "aa", 2, y, x)])) == "oracle"
    assert mc.target_protocol(_seq([Target(0, "", 1), Target(9, "", 2)])) == "states"  # clicked states
    assert mc.target_protocol(_seq([Target(0, "m"), Target(9, "aa", 2)])) == "states"  # a state among phones
    assert mc.target_protocol(_seq([Target(0, "m"), Target(9, "aa")])) == "phones"  # text, phones, TextGrid
    assert mc.target_protocol(_seq([Target(0, "m", 1, y, x), Target(9, "aa", 2, y)])) == "states"  # X not at all


def test_best_method_and_its_description():
    assert mc.best_method(CHOICE, "phones") == "dominance"
    assert mc.best_method(CHOICE, "oracle") == "manifold"
    assert mc.best_method({"best": {}}, "states") == "manifold" and mc.best_method(None, "phones") == "manifold"
    text = mc.describe(CHOICE, "phones", "dominance")
    assert text == "method: dominance, best on validation (phones protocol: RMSE X 13.9; manifold 19.3, 39 % behind)"
    assert mc.describe(CHOICE, "states", "manifold") == ("method: manifold, best on validation (states protocol: "
                                                         "RMSE X 12; next sv-hermite 12.2)")
    assert "not measured on validation: no validation split" in mc.describe({"best": {}}, "oracle", "manifold")


def test_the_choice_is_measured_once_and_keyed_by_the_data(small_manifold, tmp_path, monkeypatch):
    import engine.synthesis.validation

    calls = []

    def fake(manifold, **kw):
        calls.append(1)
        return {**CHOICE, "state_dims": 5, "validation": {"big": "diagnostics, not cached"}}

    monkeypatch.setattr(engine.synthesis.validation, "select_settings", fake)
    first = mc.choose_methods(small_manifold, cache_dir=tmp_path)
    again = mc.choose_methods(small_manifold, cache_dir=tmp_path)
    assert calls == [1] and first == again and "validation" not in again and again["state_dims"] == 5
    p = mc.choice_path(small_manifold, tmp_path)
    assert p.is_file() and p.parent.name == "method-choice"
    other = copy.copy(small_manifold)
    other.Fx_ = small_manifold.Fx_ + 1.0  # other data: another key, measured again
    assert mc.choice_path(other, tmp_path) != p
    mc.choose_methods(other, cache_dir=tmp_path)
    assert calls == [1, 1]
    p.write_text("not json")  # a damaged cache entry is measured again, not trusted
    assert mc.load_choice(small_manifold, tmp_path) is None
    mc.choose_methods(small_manifold, cache_dir=tmp_path)
    assert len(calls) == 3 and mc.load_choice(small_manifold, tmp_path) is not None


def test_state_model_synthesisers_resolve_every_kind_of_target(small_manifold):
    """A clicked state of the manifold's own graph, an F^y point and a phone label each become a state of the
    validated state model; the state-velocity Hermite spline passes through the states' mean X there."""
    from engine.synthesis.learnt_paths import prior_blend
    from engine.synthesis.state_synthesis import LearntPathSynthesizer, StateHermiteSynthesizer

    m = small_manifold
    choice = {"state_dims": 5, "n_states": 120, "n_neighbors": 20,
              "blend": {p: prior_blend(m.Fx_.shape[1]) for p in ("states", "oracle", "phones")}}
    sh = StateHermiteSynthesizer(choice=choice).fit(m)
    tg = _seq([Target(2, "", 3), Target(12, "", None, np.asarray(m.Fy_[100], np.float64)), Target(24, "aa")])
    tr = sh.synthesize(tg)
    st = tr.info["states"]
    assert tr.info["protocol"] == "states" and len(st) == 3
    assert st[1] == int(sh.model_.predict(m.Fy_[100:101, :5])[0])
    np.testing.assert_allclose(tr.Fx[[2, 12, 24]], sh.model_.inverse_.means_[st], rtol=1e-4, atol=1e-3)
    # with no learnt share the manifold method is exactly the spline
    lp = LearntPathSynthesizer(choice=choice).fit(m)
    np.testing.assert_allclose(lp.synthesize(tg).Fx, tr.Fx, atol=1e-5)
    with pytest.raises(ValueError, match="out of range"):
        sh.synthesize(_seq([Target(0, "", 10 ** 6), Target(5, "", 1)]))

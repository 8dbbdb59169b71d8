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


def _fake_choice(m, best):
    from engine.synthesis.learnt_paths import prior_blend

    return {"best": best, "state_dims": 3, "n_states": 40, "n_neighbors": 20, "frames_per_state": 30,
            "sigma": {"states/viterbi": 2.0}, "sliding_window": [4, 3, 1.0],
            "protocols": ["states", "oracle", "phones"],
            "blend": {p: prior_blend(m.Fx_.shape[1]) for p in ("states", "oracle", "phones")}, "method_validation": {},
            "val_ids": [], "note": "a test's choice"}


def test_a_build_stores_its_choice_states_and_phone_model_and_synthesis_uses_them(small_manifold, tmp_path,
                                                                                  monkeypatch):
    """fit_choice keeps the choice, the synthesiser's state centres and the best phone model on the manifold; its file
    gives them back, and the first synthesis then runs no validation, no K-means and no phone-model fit."""
    import engine.synthesis.validation
    from engine.graph.states import StateGraph
    from engine.manifold.model import Manifold
    from engine.synthesis.methods import make_synthesizer
    from engine.synthesis.sliding_window import SlidingWindowRegressor

    m = copy.copy(small_manifold)
    best = {"states": "manifold", "oracle": "sv-hermite", "phones": "sliding-window"}
    monkeypatch.setattr(engine.synthesis.validation, "select_settings", lambda manifold, **kw: _fake_choice(m, best))
    choice = mc.fit_choice(m)
    assert choice["code"] == mc.choice_code() and m.synthesis_states_.shape[1] == 3
    assert set(k.split("/")[0] for k in m.synthesis_models_) == {"sliding-window"}
    back = Manifold.load(m.save(tmp_path / "m.npz"))
    assert back.synthesis_choice_ == choice and mc.stored_choice(back) == choice
    np.testing.assert_array_equal(back.synthesis_states_, m.synthesis_states_)

    def never(*a, **k):
        raise AssertionError("measured or fitted again")

    monkeypatch.setattr(engine.synthesis.validation, "select_settings", never)
    monkeypatch.setattr(StateGraph, "_kmeans", never)
    assert mc.choose_methods(back, cache_dir=tmp_path) == choice  # from the file, not measured
    syn = make_synthesizer("manifold", back, choice=choice)
    np.testing.assert_array_equal(syn.model_.graph_.centroids_, m.synthesis_states_)
    ctx, ow, alpha = choice["sliding_window"]
    sw = make_synthesizer("sliding-window", back, context=ctx, output_window=ow, alpha=alpha)
    monkeypatch.undo()
    fresh = SlidingWindowRegressor(context=ctx, output_window=ow, alpha=alpha)
    from engine.synthesis.trajectory import phone_sequences

    fresh.fit(phone_sequences(m.corpus_.utterances, m.Fx_), m.corpus_.rate)
    u = m.corpus_.utterances[0]
    np.testing.assert_allclose(sw.model_.predict(u.phones, u.n_frames, m.corpus_.rate),
                               fresh.predict(u.phones, u.n_frames, m.corpus_.rate), rtol=1e-10, atol=1e-10)
    other = make_synthesizer("sliding-window", back, context=ctx + 2, output_window=ow, alpha=alpha)
    assert other.model_.context == ctx + 2  # other settings than the stored model's: fitted now


def test_a_choice_by_other_code_or_a_file_without_one_is_measured_at_the_first_synthesis(small_manifold, tmp_path,
                                                                                        monkeypatch):
    import engine.synthesis.stored_choice
    import engine.synthesis.validation
    from engine.manifold.model import Manifold

    old = Manifold.load(small_manifold.save(tmp_path / "old.npz"))  # a file as builds wrote them before
    assert old.synthesis_choice_ is None and old.synthesis_states_ is None and old.synthesis_models_ == {}
    calls = []

    def fake(manifold, **kw):
        calls.append(1)
        return _fake_choice(manifold, {"states": "manifold"})

    monkeypatch.setattr(engine.synthesis.validation, "select_settings", fake)
    mc.choose_methods(old, cache_dir=tmp_path)
    assert calls == [1]
    m = copy.copy(small_manifold)
    mc.fit_choice(m)
    assert mc.stored_choice(m) is not None and len(calls) == 2
    monkeypatch.setattr(engine.synthesis.stored_choice, "choice_code", lambda: "edited since")
    assert mc.stored_choice(m) is None and mc.stored_states(m, m.synthesis_choice_) is None
    mc.choose_methods(m, cache_dir=tmp_path / "other")
    assert len(calls) == 3  # the stored choice of other code is not used


def test_a_damaged_stored_choice_is_refused_naming_the_field(small_manifold, tmp_path, monkeypatch):
    import engine.synthesis.validation
    from engine.manifold.model import Manifold, ManifoldFileError

    m = copy.copy(small_manifold)
    monkeypatch.setattr(engine.synthesis.validation, "select_settings",
                        lambda manifold, **kw: _fake_choice(m, {"states": "manifold"}))
    mc.fit_choice(m)
    d = dict(np.load(m.save(tmp_path / "m.npz")))
    for key, value, field in (("synthesis_choice", np.array("{not json"), "synthesis_choice"),
                              ("synthesis_choice", np.array('{"best": 3}'), "synthesis_choice"),
                              ("synthesis_states", np.zeros((5, 7)), "synthesis_states"),
                              ("synthesis_states", np.full((5, 3), np.nan), "synthesis_states")):
        bad = {**d, key: value}
        with open(tmp_path / "bad.npz", "wb") as fh:
            np.savez(fh, **bad)
        with pytest.raises(ManifoldFileError, match=field):
            Manifold.load(tmp_path / "bad.npz")


def test_a_stored_dominance_model_predicts_as_the_one_fitted(small_manifold):
    from engine.files.persist import dump_estimator
    from engine.synthesis.dominance import DominanceModel
    from engine.synthesis.stored_choice import stored_model
    from engine.synthesis.trajectory import phone_sequences

    m = copy.copy(small_manifold)
    c = m.corpus_
    model = DominanceModel(max_iter=5).fit(phone_sequences(c.utterances[:6], m.Fx_), c.rate)
    m.synthesis_choice_ = {"best": {"phones": "dominance"}, "blend": {}, "code": mc.choice_code()}
    m.synthesis_models_ = dump_estimator(model, "dominance")
    back = stored_model(m, "dominance", DominanceModel(max_iter=5))
    u = c.utterances[7]
    np.testing.assert_allclose(back.predict(u.phones, u.n_frames, c.rate), model.predict(u.phones, u.n_frames, c.rate),
                               rtol=1e-9, atol=1e-9)
    assert stored_model(m, "dominance", DominanceModel()) is None  # fitted with other parameters

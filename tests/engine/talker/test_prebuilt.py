"""The shipped manifold of the default talker: written, read back on the regenerated corpus, refused when stale,
and the same as a fresh fit.

The round trip runs on a short talker (written and read here); the checks of the shipped file
itself run on the default talker's regenerated corpus, and the slow one fits it afresh.
"""
from __future__ import annotations

import copy

import numpy as np
import pytest

from engine.talker import prebuilt as pb

SHORT = {"preset": "small", "n_sentences": 14}


def _short_manifold(monkeypatch):
    import engine.synthesis.validation
    from engine.manifold.model import Manifold
    from engine.synthesis.learnt_paths import prior_blend
    from engine.synthesis.method_choice import fit_choice
    from engine.talker.synthetic import SyntheticTalker

    corpus = SyntheticTalker(**SHORT).generate()
    m = Manifold().fit(corpus)
    choice = {"best": {"states": "manifold"}, "state_dims": 3, "n_states": 20, "n_neighbors": 20,
              "blend": {"states": prior_blend(m.Fx_.shape[1])}, "note": "a test's choice"}
    with monkeypatch.context() as mp:  # a choice without its validation: this test is about the file
        mp.setattr(engine.synthesis.validation, "select_settings", lambda manifold, **kw: choice)
        fit_choice(m)
    return corpus, m


def test_round_trip_on_the_regenerated_corpus_and_what_is_refused(monkeypatch, tmp_path):
    from engine.manifold.model import ManifoldFileError

    corpus, m = _short_manifold(monkeypatch)
    path = pb.write_prebuilt(m, tmp_path / "t.npz", **SHORT)
    stored = set(np.load(path).files)
    assert not stored & {"Fx", "Fxv", "G", "embedding/embedding_", "embedding/reference_"}
    assert not any(k.startswith("corpus_") for k in stored)  # the corpus is regenerated, never shipped
    back, why = pb.load_prebuilt(corpus, path=path, **SHORT)
    assert why == "shipped" and back.corpus_ is corpus
    for a in ("Fx_", "Fxv_", "G_", "Fy_", "state_x_", "synthesis_states_"):
        np.testing.assert_array_equal(getattr(back, a), getattr(m, a), err_msg=a)
    np.testing.assert_array_equal(back.tangent_.s_, m.tangent_.s_)
    np.testing.assert_array_equal(back.states_.labels_, m.states_.labels_)
    assert back.synthesis_choice_ == m.synthesis_choice_ and back.get_params() == m.get_params()
    np.testing.assert_allclose(back.project(corpus.frames[:40], np.array([[0, 40]])), m.project(corpus.frames[:40],
                               np.array([[0, 40]])), rtol=1e-5, atol=1e-4)

    from engine.talker.synthetic import SyntheticTalker

    other = SyntheticTalker(**SHORT, seed=3).generate()
    assert pb.load_prebuilt(other, path=path, **SHORT)[0] is None  # another corpus
    moved = copy.copy(corpus)
    moved.frames = corpus.frames + np.float32(0.5)  # the same utterances, other frames (another RNG, say)
    got, why = pb.load_prebuilt(moved, path=path, **SHORT)
    assert got is None and "regenerated frames differ" in why
    got, why = pb.load_prebuilt(corpus, path=path, preset="small", n_sentences=15)
    assert got is None and "other code or for another talker" in why
    import engine.manifold.model

    monkeypatch.setattr(engine.manifold.model, "algorithm_fingerprint", lambda params=None: "edited")
    assert pb.load_prebuilt(corpus, path=path, **SHORT)[0] is None  # made by other fitting code
    monkeypatch.undo()
    assert pb.load_prebuilt(corpus, path=tmp_path / "none.npz", **SHORT)[0] is None
    path.write_bytes(path.read_bytes()[:2000])
    with pytest.raises(ManifoldFileError, match="t.npz"):
        pb.load_prebuilt(corpus, path=path, **SHORT)


@pytest.fixture(scope="module")
def default_corpus():
    from engine.talker.synthetic import load_synthetic

    return load_synthetic(preset=pb.PRESET)


def test_the_shipped_manifold_was_made_by_this_code():
    path = pb.prebuilt_path()
    assert path.is_file(), f"{path} is missing: make it with 'python -m engine.talker.prebuilt'"
    key = str(np.load(path)["prebuilt_key"])
    assert key == pb.prebuilt_key(), (
        f"{path} was made by other code than this (the talker, the fit or the synthesis choice changed since): "
        "make it again with 'python -m engine.talker.prebuilt' (a few minutes) and commit it")


def test_the_shipped_manifold_fits_the_regenerated_talker(default_corpus):
    """Read back on the default talker's corpus generated here, and checked against computations made now: F^y
    of sampled frames through the embedding, every frame's state, the inverse map at sampled states."""
    m, why = pb.load_prebuilt(default_corpus)
    assert m is not None, why
    rng = np.random.default_rng(0)
    rows = np.sort(rng.choice(len(m.Fy_), 300, replace=False))
    Fy_now = m.embedding_.transform(m.G_[rows])
    scale = np.sqrt(np.mean(np.asarray(m.Fy_, np.float64) ** 2))
    assert np.max(np.abs(Fy_now - m.Fy_[rows])) < 1e-3 * scale
    np.testing.assert_array_equal(m.states_.predict(m.Fy_), m.states_.labels_)
    ks = rng.choice(m.states_.centroids_.shape[0], 20, replace=False)
    x_now = m.inverse_map.transform(np.asarray(m.states_.centroids_[ks], np.float64))
    xscale = np.sqrt(np.mean(np.asarray(m.Fx_, np.float64) ** 2))
    assert np.max(np.abs(x_now - m.state_x_[ks])) < 1e-3 * xscale
    from engine.synthesis.method_choice import stored_choice

    assert stored_choice(m) is not None and m.synthesis_states_ is not None


@pytest.mark.slow
def test_a_fresh_fit_of_the_default_talker_is_the_shipped_manifold(default_corpus):
    """The whole shipped file against the fit and the synthesis choice made now (minutes on two cores)."""
    shipped, why = pb.load_prebuilt(default_corpus)
    assert shipped is not None, why
    d = pb.compare(pb.fresh(), shipped)
    assert d["choice"] and d["n_neighbors"] and d["n_states"], d
    assert d["fy"] < 1e-3 and d["tangent"] < 1e-2 and d["centroids"] < 1e-2 and d["state_x"] < 1e-2, d
    assert d["classes"] > 0.99 and d["labels"] > 0.99 and d["synthesis_states"] < 1e-2, d

import numpy as np
import pytest

from engine.phonetics.targets import targets_from_phones, targets_from_utterance
from engine.synthesis.unitselection import (
    OVERLAP_TABLE,
    UnitSelectionSynthesizer,
    crossfade_weights,
    lip_class,
    overlap_fraction,
)


def test_overlap_table_is_the_papers_table_1():
    P, I, N = "protected", "invisible", "normal"  # noqa: E741 (the letters of the paper's table)
    expected = {(P, P): (50, 50), (P, I): (77, 23), (P, N): (55, 45),
                (I, P): (23, 77), (I, I): (50, 50), (I, N): (27, 73),
                (N, P): (45, 55), (N, I): (77, 23), (N, N): (50, 50)}
    for (fw, bw), (f, b) in expected.items():
        assert overlap_fraction(fw, bw) == pytest.approx(f / 100)
        assert f + b == 100 and OVERLAP_TABLE[(fw, bw)] == f
    with pytest.raises(ValueError, match="unknown lip-reading classes"):
        overlap_fraction("protected", "loud")


def test_lip_classes_follow_the_second_paper():
    assert [lip_class(p) for p in ("f", "v", "m", "p")] == ["protected"] * 4
    assert [lip_class(p) for p in ("t", "d", "g", "k", "l")] == ["invisible"] * 5
    assert [lip_class(p) for p in ("b", "aa", "s", "w")] == ["normal"] * 4
    assert lip_class("sil") == "normal" and lip_class("P") == "protected"


def test_crossfade_point_falls_where_the_table_puts_it():
    mid_a, mid_b = 1.0, 2.0
    t = np.linspace(0.5, 2.5, 2001)
    for (fw, bw), pct in OVERLAP_TABLE.items():
        w = crossfade_weights(t, mid_a, mid_b, overlap_fraction(fw, bw))
        half = t[np.argmin(np.abs(w - 0.5))]
        assert half == pytest.approx(mid_a + pct / 100 * (mid_b - mid_a), abs=1e-3)
        assert w[t <= mid_a].max() == 0.0 and w[t >= mid_b].min() == 1.0
        assert np.all(np.diff(w) >= 0)
    # protected before invisible: the protected phone's unit keeps more of the overlap than the reverse
    assert overlap_fraction("protected", "invisible") > overlap_fraction("invisible", "protected")


@pytest.fixture(scope="module")
def usel(small_manifold):
    return UnitSelectionSynthesizer().fit(small_manifold)


def test_own_phones_resynthesise_a_training_utterance_exactly(small_manifold, usel):
    m = small_manifold
    u = m.corpus_.utterances[4]
    tg = targets_from_utterance(m, u.id).phones_only()
    tr = usel.synthesize(tg)
    assert set(tr.info["joins"]) == {"contiguous"}
    assert all(uid == u.id for uid, _ in tr.info["units"])
    np.testing.assert_allclose(tr.Fx, m.Fx_[u.start:u.stop], rtol=0, atol=1e-4 * np.abs(m.Fx_).max())


def test_output_is_continuous_when_units_come_from_elsewhere(small_manifold):
    m = small_manifold
    u = m.corpus_.utterances[4]
    syn = UnitSelectionSynthesizer(exclude_utterances=[u.id], context=5).fit(m)
    tr = syn.synthesize(targets_from_utterance(m, u.id).phones_only())
    assert all(uid != u.id for uid, _ in tr.info["units"])
    kinds = set(tr.info["joins"])
    assert kinds - {"contiguous"}, kinds  # some real joins happened
    assert tr.Fx.shape == (u.n_frames, m.Fx_.shape[1]) and np.isfinite(tr.Fx).all()
    step = np.linalg.norm(np.diff(tr.Fx, axis=0), axis=1)
    raw = UnitSelectionSynthesizer(exclude_utterances=[u.id], context=5, smoothing=0).fit(m).synthesize(
        targets_from_utterance(m, u.id).phones_only())
    raw_step = np.linalg.norm(np.diff(raw.Fx, axis=0), axis=1)
    assert raw.info["units"] == tr.info["units"]
    if "hard" in kinds:  # the 5 % smoothing spreads every hard jump over several frames
        assert step.max() <= 0.5 * raw_step.max()
    # no step is more than twice the fastest movement the talker ever made between two frames
    assert step.max() <= 2 * np.linalg.norm(m.Fxv_, axis=1).max()


def test_hard_joins_are_smoothed(small_manifold, usel):
    m = small_manifold
    # a phone pair never seen together in one order forces hard joins somewhere
    tg = targets_from_phones(m, "sil 0.2 zh 0.1 oy 0.15 zh 0.1 sil 0.2")
    tr = usel.synthesize(tg)
    assert len(tr.info["joins"]) == 4
    assert "hard" in tr.info["joins"]
    step = np.linalg.norm(np.diff(tr.Fx, axis=0), axis=1)
    raw = UnitSelectionSynthesizer(smoothing=0).fit(m).synthesize(tg)
    assert step.max() < np.linalg.norm(np.diff(raw.Fx, axis=0), axis=1).max()


def test_parameters_and_bad_input(small_manifold, usel):
    with pytest.raises(ValueError, match="context must be one of 3, 5"):
        UnitSelectionSynthesizer(context=4).fit(small_manifold)
    with pytest.raises(ValueError, match=r"smoothing must be in \[0, 0.5\)"):
        UnitSelectionSynthesizer(smoothing=0.7).fit(small_manifold)
    u = small_manifold.corpus_.utterances[0]
    all_ids = [x.id for x in small_manifold.corpus_.utterances]
    syn = UnitSelectionSynthesizer(exclude_utterances=all_ids).fit(small_manifold)
    with pytest.raises(ValueError, match="has no usable unit"):
        syn.synthesize(targets_from_utterance(small_manifold, u.id).phones_only())

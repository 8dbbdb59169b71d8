"""Conditions of the synthetic talker with a known difference, and where that difference is."""
import numpy as np
import pytest

from engine.talker.conditions import DEFAULT_SIZE, apply_effect, condition_corpus
from engine.talker.lipmodel import CONTROL_NAMES

JAW, CLOSURE = CONTROL_NAMES.index("jaw"), CONTROL_NAMES.index("closure")


def test_paired_tokens_say_each_sentence_in_every_condition_with_their_own_articulation():
    cc = condition_corpus(conditions={"a": "none", "b": "none"}, n_texts=3, repetitions=2, speakers=2)
    f = cc.fields
    assert len(cc.corpus.utterances) == 3 * 2 * 2 * 2
    for t in np.unique(f["text"]):
        sel = f["text"] == t
        assert sorted(f["condition"][sel].tolist()) == ["a"] * 4 + ["b"] * 4
        assert sorted(set(f["speaker"][sel])) == ["spk1", "spk2"]
    assert (cc.effect_mm == 0).all()
    lengths = {u.n_frames for u in cc.corpus.utterances if u.text == cc.corpus.utterances[0].text}
    assert len(lengths) > 1  # each token at its own rate


def test_unpaired_conditions_say_different_sentences():
    cc = condition_corpus(conditions={"a": "none", "b": "none"}, n_texts=2, paired=False)
    by = {lv: set(cc.fields["text"][cc.fields["condition"] == lv]) for lv in ("a", "b")}
    assert len(by["a"]) == 2 and len(by["b"]) == 2 and not by["a"] & by["b"]


def test_the_bilabial_release_moves_the_lips_only_from_a_bilabial_closure_to_the_next_phone():
    cc = condition_corpus(n_texts=4, seed=3)
    c, f = cc.corpus, cc.fields
    assert cc.effects == {"a": ("none", 0.0), "b": ("bilabial_release", DEFAULT_SIZE["bilabial_release"])}
    moved = cc.effect_mm > 1e-4
    window = np.zeros(c.n_frames, bool)
    for u, cond in zip(c.utterances, f["condition"]):
        if cond == "a":
            assert not moved[u.start:u.stop].any()
            continue
        t = np.arange(u.n_frames) / c.rate
        for k, p in enumerate(u.phones):
            if p.label in ("p", "b", "m") and k + 1 < len(u.phones):
                nxt = u.phones[k + 1]
                window[u.start:u.stop] |= (t >= p.start) & (t <= nxt.start + 0.5 * (nxt.end - nxt.start) + 1e-9)
    assert moved.any() and not (moved & ~window).any()
    assert cc.effect_mm.max() > 1.0  # mm


def test_apply_effect_bump_and_lag():
    from engine.recordings.corpus import PhoneInterval

    rate = 100.0
    C = np.zeros((100, len(CONTROL_NAMES)))
    phones = (PhoneInterval(0.0, 0.2, "aa"), PhoneInterval(0.2, 0.4, "p"), PhoneInterval(0.4, 0.6, "aa"),
              PhoneInterval(0.6, 1.0, "aa"))
    out = apply_effect(C, phones, rate, "bilabial_release", 0.5)
    t = np.arange(100) / rate
    bump = out[:, JAW]
    assert bump.max() == pytest.approx(0.5, abs=1e-3)
    peak = 0.2 + 0.3 * 0.2 + 0.5 * 0.7 * 0.2  # half-way from the closure peak to the phone's end
    assert t[np.argmax(bump)] == pytest.approx(peak, abs=0.011)
    assert (bump[t < 0.26 - 1e-9] == 0).all() and (bump[t > 0.5 + 1e-9] == 0).all()
    assert (np.delete(out, JAW, axis=1) == 0).all()
    # slow closing: the jaw falls (closes) late, rises (opens) at once; the closure rises late
    C = np.zeros((60, len(CONTROL_NAMES)))
    C[:20, JAW], C[40:, JAW] = 1.0, 1.0
    C[20:40, CLOSURE] = 1.0
    out = apply_effect(C, (), 60.0, "slow_closing", 0.1)
    assert out[25, JAW] > 0.3 and out[40, JAW] == 1.0
    assert out[21, CLOSURE] < 0.5 and out[39, CLOSURE] > 0.9 and out[40, CLOSURE] == 0.0


@pytest.mark.parametrize("kw, match", [
    ({"conditions": {"a": "none", "b": "louder"}}, "effect='louder'"),
    ({"conditions": {"a": "none"}}, "at least two conditions"),
    ({"n_texts": 0}, "n_texts=0"),
    ({"conditions": {"a": "none", "b": ("slow_closing", -1)}}, "size=-1"),
])
def test_bad_parameters_are_named(kw, match):
    with pytest.raises(ValueError, match=match):
        condition_corpus(**kw)

"""Phone inventory, pronunciation through the CMU dictionary, duration model."""
from __future__ import annotations

import numpy as np
import pytest

from engine.files.assets import asset_path
from engine.phonetics.phones import (
    CONSONANTS,
    PAPER_COUNTS,
    PAUSE,
    PHONES,
    VOWELS,
    DurationModel,
    UnknownPhoneError,
    UnknownWordError,
    cmu_to_paper,
    is_vowel,
    parse_phones,
    phone_class,
    pronounce,
)


def test_inventory_is_the_papers_table_1_plus_documented_extras():
    assert set(PAPER_COUNTS) == set(CONSONANTS) | set(VOWELS)
    assert len(CONSONANTS) == 24 and len(VOWELS) == 18
    assert set(PHONES) - set(PAPER_COUNTS) == {"uw", "er", PAUSE}


def test_hello_world():
    assert pronounce("hello world") == ["hh", "ax", "l", "ow", "w", "er", "l", "d"]
    assert pronounce("Hello, world!", pauses=True) == [PAUSE] + pronounce("hello world") + [PAUSE]


@pytest.mark.parametrize("word, phones", [
    ("there", ["dh", "ea"]),      # square: non-rhotic centring diphthong
    ("near", ["n", "ia"]),
    ("car", ["k", "aa"]),         # start
    ("hot", ["hh", "oh", "t"]),   # lot vowel spelt with o
    ("father", ["f", "aa", "dh", "ax"]),
    ("very", ["v", "eh", "r", "iy"]),  # prevocalic r kept
    ("party", ["p", "aa", "t", "iy"]),  # coda r dropped
])
def test_british_mapping(word, phones):
    assert pronounce(word) == phones


def test_stress_digits_removed_and_schwa():
    assert cmu_to_paper(["AH0", "B", "AH1", "V"], "above") == ["ax", "b", "ah", "v"]
    assert cmu_to_paper(["B", "ER1", "D"], "bird") == ["b", "er", "d"]
    assert cmu_to_paper(["B", "AH1", "T", "ER0"], "butter") == ["b", "ah", "t", "ax"]


def test_every_pronounced_phone_is_in_the_inventory():
    text = "the quick brown fox jumps over the lazy dog while measuring thousands of yellow chairs"
    phones = pronounce(text)
    assert len(phones) > 40
    assert all(p in PHONES and p == p.lower() and not any(ch.isdigit() for ch in p) for p in phones)


def test_unknown_word_names_the_word_and_suggests_phones():
    with pytest.raises(UnknownWordError) as err:
        pronounce("hello qzxvwordz")
    msg = str(err.value)
    assert "qzxvwordz" in msg and "[" in msg
    with pytest.raises(UnknownWordError, match="digits"):
        pronounce("route 66")


def test_bracketed_phone_strings():
    assert pronounce("the [g r ax f ow] sat") == ["dh", "ax", "g", "r", "ax", "f", "ow", "s", "ae", "t"]
    assert parse_phones("P AA sil") == ["p", "aa", "sil"]
    with pytest.raises(UnknownPhoneError, match="xx"):
        pronounce("[k xx t]")


def test_phone_classes():
    assert [phone_class(p) for p in ("p", "b", "m")] == ["bilabial"] * 3
    assert phone_class("f") == phone_class("v") == "labiodental"
    assert phone_class("th") == "dental" and phone_class("s") == "alveolar" and phone_class("k") == "velar"
    assert phone_class(PAUSE) == "pause"
    assert all(is_vowel(v) for v in VOWELS) and not any(is_vowel(c) for c in CONSONANTS)
    with pytest.raises(UnknownPhoneError):
        phone_class("zz")


def test_duration_means_are_phonetically_ordered():
    dm = DurationModel()
    assert dm.mean("aa") > dm.mean("ih") > dm.mean("ax")
    assert dm.mean("ay") > dm.mean("p") and dm.mean("s") > dm.mean("t")
    assert dm.mean(PAUSE) > dm.mean("aa")
    assert all(0.03 <= dm.mean(p) <= 0.3 for p in PHONES)
    assert DurationModel(tempo=2.0).mean("aa") == pytest.approx(dm.mean("aa") / 2)


def test_drawn_durations_are_seeded_and_keep_the_mean():
    dm = DurationModel()
    phones = ["aa"] * 4000
    a, b = dm.durations(phones, rng=3), dm.durations(phones, rng=3)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, dm.durations(phones, rng=4))
    assert a.mean() == pytest.approx(dm.mean("aa"), rel=0.03)
    assert a.std() == pytest.approx(dm.sd("aa"), rel=0.1)
    assert a.min() >= dm.min_duration
    np.testing.assert_array_equal(dm.durations(["p", "aa"]), [dm.mean("p"), dm.mean("aa")])


def test_duration_model_rejects_bad_parameters():
    with pytest.raises(ValueError, match="tempo"):
        DurationModel(tempo=0)
    with pytest.raises(ValueError, match="sd_ratio"):
        DurationModel(sd_ratio=-1)


def test_asset_path():
    assert asset_path("wordlist.txt").is_file()
    with pytest.raises(FileNotFoundError, match="no-such-asset.txt"):
        asset_path("no-such-asset.txt")


def test_word_list_phone_frequencies_resemble_table_1():
    words = [w for w in asset_path("wordlist.txt").read_text().split("\n") if w and not w.startswith("#")]
    assert len(words) >= 2000
    counts = dict.fromkeys(PAPER_COUNTS, 0)
    for w in words:
        for p in pronounce(w):
            if p in counts:
                counts[p] += 1
    ours = np.array([counts[p] for p in PAPER_COUNTS], float)
    paper = np.array(list(PAPER_COUNTS.values()), float)
    assert (ours > 0).all()
    assert np.corrcoef(ours, paper)[0, 1] > 0.9


def test_the_dictionary_lookup_gives_what_a_full_parse_keeps_for_every_word():
    """The binary search over the dictionary's lines (a handful out of order) finds, for each of its words, the
    first pronunciation a full parse keeps; variant marks, other cases and absent words find nothing."""
    import re

    from engine.phonetics.phones import _cmu_entry, _cmu_text

    full: dict[str, str] = {}
    for w, pron in re.findall(r"^([^ (\n]+) ([^#\n]+)", _cmu_text(), flags=re.M):
        full.setdefault(w, pron)
    assert len(full) > 120_000
    wrong = [w for w in full if _cmu_entry(w) != full[w]]
    assert wrong == []
    for absent in ("", "a(2)", "Bob", "zzqx", "bob meets", "#"):
        assert _cmu_entry(absent) is None, absent

"""The design a comparison reads off its levels, speakers and pairing field, and what it refuses."""
import math

import numpy as np
import pytest

from engine.comparison.compare import default_contrasts
from engine.comparison.design import ComparisonError, resolve_design


def test_one_speaker_is_between_utterances():
    d = resolve_design(["a", "b", "a", "b", "a", "b", "c"], "a", "b")
    assert d.kind == "between utterances"
    assert d.utterances.tolist() == [0, 1, 2, 3, 4, 5]
    assert d.group.tolist() == [0, 1, 0, 1, 0, 1]
    assert d.n_arrangements == math.comb(6, 3) and d.testable and d.can_bootstrap
    assert "a 3 vs b 3 utterances" in d.describe()


def test_levels_varying_within_speakers_are_permuted_within_them():
    levels = ["a", "b", "a", "b", "a", "a"]
    speakers = ["S1", "S1", "S2", "S2", "S3", "S3"]
    d = resolve_design(levels, "a", "b", by="emotion", speakers=speakers)
    assert d.kind == "within speaker"
    assert d.utterances.tolist() == [0, 1, 2, 3]  # S3 holds one level only: left out
    assert d.stratum_names == ("S1", "S2")
    assert d.n_arrangements == 4 and not d.testable
    assert any("speakers holding only one level" in n for n in d.notes)


def test_levels_nested_in_speakers_resample_whole_speakers():
    levels = ["F"] * 4 + ["M"] * 4
    speakers = ["s1", "s1", "s2", "s2", "s3", "s3", "s4", "s4"]
    d = resolve_design(levels, "F", "M", by="sex", speakers=speakers)
    assert d.kind == "between speakers" and d.unit_name == "speaker"
    assert d.n_units == (2, 2) and d.n_arrangements == 6 and not d.testable
    assert d.reason.startswith("F has 2 and M has 2 speakers: whole speakers are what is resampled")
    # one speaker per level: the level cannot be told from the speaker
    d = resolve_design(["F", "F", "M", "M"], "F", "M", by="sex", speakers=["s1", "s1", "s2", "s2"])
    assert any("cannot be told from a difference between s1 and s2" in n for n in d.notes)


def test_the_speaker_field_compares_speakers_as_individuals():
    d = resolve_design(["A"] * 3 + ["B"] * 3, "A", "B", by="speaker", speakers=["A"] * 3 + ["B"] * 3)
    assert d.kind == "between utterances" and d.n_arrangements == 20 and d.testable
    assert any("compared as individuals" in n for n in d.notes)


def test_paired_blocks_and_what_they_leave_out():
    levels = ["a", "b", "a", "b", "a", ""]
    texts = ["t1", "t1", "t2", "t2", "t3", "t3"]
    d = resolve_design(levels, "a", "b", pairs=texts, paired_by="text")
    assert d.kind == "within blocks" and d.bootstrap == "blocks"
    assert d.utterances.tolist() == [0, 1, 2, 3] and d.stratum_names == ("t1", "t2")
    assert d.n_arrangements == 4
    assert any("blocks holding only one level" in n for n in d.notes)
    # 5 pairs: 32 arrangements, testable
    d = resolve_design(["a", "b"] * 5, "a", "b", pairs=np.repeat([f"t{i}" for i in range(5)], 2), paired_by="text")
    assert d.n_arrangements == 32 and d.testable and d.can_bootstrap


def test_paired_by_text_within_each_speaker_when_the_level_varies_within_speakers():
    levels = ["a", "b", "a", "b"]
    texts = ["t1", "t1", "t1", "t1"]
    speakers = ["S1", "S1", "S2", "S2"]
    d = resolve_design(levels, "a", "b", by="emotion", speakers=speakers, pairs=texts, paired_by="text")
    assert d.stratum_names == ("t1 / S1", "t1 / S2")
    assert d.paired_by == "text and speaker"


def test_one_utterance_per_level_cannot_be_tested_and_says_why():
    d = resolve_design(["F01", "M01"], "F01", "M01", by="speaker", speakers=["F01", "M01"], pairs=["s", "s"],
                       paired_by="text")
    assert not d.testable and not d.can_bootstrap and d.n_arrangements == 2
    assert d.reason.startswith("one utterance per level (F01: 1, M01: 1)")
    assert "no p-value can fall below 0.5" in d.reason and "3 utterances per level" in d.reason
    assert "descriptive only" in d.describe()


@pytest.mark.parametrize("levels, a, b, match", [
    (["a", "b"], "a", "c", "field 'level' has no level 'c'; its levels \\(utterances\\): a \\(1\\), b \\(1\\)"),
    (["a", "b"], "a", "a", "level 'a' given twice"),
])
def test_bad_levels_are_named(levels, a, b, match):
    with pytest.raises(ComparisonError, match=match):
        resolve_design(levels, a, b)


def test_levels_that_never_share_a_text_are_refused_naming_both():
    with pytest.raises(ComparisonError, match="levels 'angry' and 'neutral' of 'emotion' never share a text: no "
                                              "text value has utterances of both \\(e.g. angry: t1; neutral: t2\\)"):
        resolve_design(["angry", "neutral"], "angry", "neutral", by="emotion", pairs=["t1", "t2"], paired_by="text")


def test_default_contrasts():
    assert default_contrasts(["b", "a", "b"], "x") == [("a", "b")]
    assert default_contrasts(["n", "a", "s"], "emotion", ["n", "a", "s"]) == [("n", "a"), ("n", "s")]
    with pytest.raises(ComparisonError, match="'speaker' has one level \\(F01 \\(2\\)\\); a comparison needs two"):
        default_contrasts(["F01", "F01"], "speaker")
    with pytest.raises(ComparisonError, match="has 3 levels: .*choose two"):
        default_contrasts(["n", "a", "s"], "emotion")

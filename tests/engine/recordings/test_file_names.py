"""The structure of a lab's file names, and the speaker suggestions made from it: right on the names seen."""
from __future__ import annotations

import re

import pytest

from engine.recordings.file_names import crossed_split, name_structure
from engine.recordings.metadata_sources import FieldPattern
from engine.recordings.speakers import SpeakerRule, check_assignment, suggest_fields

EMOTIONS = ("NE", "AN", "HA", "SA", "FE", "DI", "SU")
#: the issue's corpus: three speakers of different code lengths, seven emotions, sixteen texts
SPEAKERS = (("XYZ", "F"), ("ABCD", "M"), ("EF", "F"))


def names(speakers=SPEAKERS, emotions=EMOTIONS, texts=16, ext=".mat"):
    return [f"/lab/{s}{x}{e}{t:02d}{ext}" for s, x in speakers for e in emotions for t in range(1, texts + 1)]


def test_a_speaker_code_fused_with_an_emotion_code_is_split_into_three_speakers():
    st = name_structure(names())
    assert [n for n, _ in st.fields] == ["speaker", "condition", "item"]
    assert st.speakers == {"XYZF": 112, "ABCDM": 112, "EFF": 112}
    assert len(st.levels("condition")) == 7 and st.crossed_with_speaker("condition")
    # what the description says is what the pattern gives
    pat = FieldPattern("re:" + st.pattern)
    got = [pat.match(p) for p in names()]
    assert {g["speaker"] for g in got} == {"XYZF", "ABCDM", "EFF"} and {g["condition"] for g in got} == set(EMOTIONS)


def test_one_speakers_folder_is_one_speaker_with_conditions_not_seven_speakers():
    one = [p for p in names() if "/XYZF" in p]
    st = name_structure(one)
    assert st.speakers == {"XYZF": 112} and not st.plausible_speakers()
    assert check_assignment(one, [""] * len(one), rule=None) == []  # no "pool of speakers" warning
    note = suggest_fields(one)
    assert "speaker 1 level (XYZF 112 files)" in note and "condition 7 levels" in note


def test_the_fused_letter_rule_is_warned_about_with_the_split_that_fits():
    paths = names()
    rule = "re:^([A-Za-z]+)"
    speakers = [SpeakerRule(rule)(p) for p in paths]
    assert len(set(speakers)) == 21
    msgs = check_assignment(paths, speakers, rule=rule)
    assert len(msgs) == 1
    m = msgs[0]
    assert "gave 21 speakers" in m and "3 speakers x 7 condition levels x 16 item levels" in m
    assert "speaker 3 levels (XYZF 112, ABCDM 112, EFF 112 files)" in m
    pat = re.search(r"--fields-from 're:(.*?)'", m).group(1)
    assert {FieldPattern(pat).match(p)["speaker"] for p in paths} == {"XYZF", "ABCDM", "EFF"}


def test_no_rule_on_a_pooled_folder_suggests_the_three_speakers():
    paths = names()
    (m,) = check_assignment(paths, [""] * len(paths), rule=None)
    assert "all 336 inputs are one unnamed speaker" in m and "3 speakers x 7 condition levels" in m


def test_a_right_rule_is_not_questioned():
    paths = names()
    rule = r"re:^([A-Z]+?)[FM][A-Z]{2}[0-9]+\."
    assert check_assignment(paths, [SpeakerRule(rule)(p) for p in paths], rule=rule) == []


def test_separated_names_and_two_sample_files():
    st = name_structure(["F01_B01_S01_R01_N.mat", "M01_B01_S01_R01_N.mat"])
    assert st.speakers == {"F01": 1, "M01": 1} and st.plausible_speakers()
    assert FieldPattern("re:" + st.pattern).match("F01_B02_S07_R01_F.mat") == {"speaker": "F01"}
    mocha = name_structure(["fsew0_001", "fsew0_002", "msak0_001", "msak0_002"])
    assert mocha.speakers == {"fsew0": 2, "msak0": 2} and mocha.levels("part") == {"001": 2, "002": 2}


@pytest.mark.parametrize("paths", [["a.mat"], ["take1.mat", "notes_final.mat"], ["AB01.mat", "AB-2.mat"]])
def test_names_that_share_no_scheme_get_no_structure(paths):
    assert name_structure(paths) is None


def test_crossed_split_needs_most_combinations():
    assert crossed_split(["XYZFNE", "XYZFAN", "ABCMNE", "ABCMAN"]) == (2, "crossed")
    assert crossed_split(["XYZFNE", "ABCMAN"]) is None  # two combinations of four: nothing says they cross
    assert crossed_split(["XYZFNE", "XYZFAN"]) == (2, "common")

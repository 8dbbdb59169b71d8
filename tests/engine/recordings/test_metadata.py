"""Per-utterance metadata fields: from file-name patterns and lab metadata tables, stored in corpus and manifold
files (older files still load), carried through subsets, joins and resampling, and read by level."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from engine.recordings.corpus import Corpus, CorpusError, Utterance
from engine.recordings.metadata import (
    MetadataError,
    check_field_name,
    field_levels,
    field_names,
    field_values,
    frame_levels,
    require_field,
    utterance_fields,
    utterances_by_level,
    with_fields,
)
from engine.recordings.metadata_sources import FieldPattern, assign_fields, read_metadata_table

ISSUE_PATTERN = r"re:^(?P<speaker>[A-Z]+?)(?P<sex>[FM])(?P<emotion>[A-Z]{2})(?P<text>[0-9]+)$"


def _corpus(n=6, fields=None):
    rng = np.random.default_rng(0)
    utts, pos = [], 0
    for k in range(n):
        m = 10 + k
        u = Utterance(f"u{k}", pos, pos + m)
        utts.append(with_fields(u, fields[k]) if fields else u)
        pos += m
    return Corpus(frames=rng.normal(size=(pos, 6)).astype(np.float32), rate=60.0, utterances=utts)


def test_the_issue_pattern_splits_speaker_sex_emotion_text():
    pat = FieldPattern(ISSUE_PATTERN)
    assert pat.match("/data/XYZFIA01.mat") == {"speaker": "XYZ", "sex": "F", "emotion": "IA", "text": "01"}
    assert pat.match("ABCDMNE16.pos") == {"speaker": "ABCD", "sex": "M", "emotion": "NE", "text": "16"}
    assert pat.match("notes.txt") is None


@pytest.mark.parametrize("spec, message", [
    ("re:^([A-Z]+)", "has no named group"),
    ("re:^(?P<spk>[A-Z", "not a regular expression"),
    ("re:(?P<class>[A-Z]+)", "is a column the tables already have"),
    ("re:(?P<fx_1>[A-Z]+)", "is a column the tables already have"),
])
def test_a_pattern_that_cannot_give_fields_is_refused(spec, message):
    with pytest.raises(MetadataError, match=message):
        FieldPattern(spec)


def test_a_pattern_that_matches_nothing_or_misses_files_names_them():
    pat = FieldPattern(ISSUE_PATTERN)
    with pytest.raises(MetadataError, match=r"matches none of the 2 file names .*: 0021, 0022"):
        pat.fields(["0021.pos", "0022.pos"])
    with pytest.raises(MetadataError, match=r"does not match 1 of the 3 file names .*: XYZFIA1b"):
        pat.fields(["XYZFIA01.pos", "XYZFIA02.pos", "XYZFIA1b.pos"])


def _table(tmp_path, text, name="meta.csv", encoding="utf-8"):
    p = tmp_path / name
    p.write_bytes(text.encode(encoding))
    return p


def test_a_spreadsheet_csv_with_bom_semicolons_and_na_reads(tmp_path):
    p = _table(tmp_path, "\ufeffFile;Speaker ID;Sex;Group;\r\n"
                         "XYZFIA01.pos;XYZ;F;NA;\r\nXYZFIA02.pos;XYZ;F;control;\r\n")
    t = read_metadata_table(p)
    assert t.key == "File" and t.fields == ["speaker_id", "sex", "group"]
    assert t.rows["XYZFIA01.pos"] == {"speaker_id": "XYZ", "sex": "F", "group": ""}
    assert t.lookup("/x/XYZFIA02.pos") == "XYZFIA02.pos" and t.lookup("xyzfia02.POS") == "XYZFIA02.pos"


@pytest.mark.parametrize("text, message", [
    ("file,speaker\na.pos,X\na.pos,Y\n", r"line 3: file 'a.pos' has a row already \(line 2\)"),
    ("file,speaker\n,X\n", r"line 2: the file-name column 'file' is empty"),
    ("file,speaker\na.pos,X,extra\n", r"line 2: 3 cells but the header has 2 columns"),
    ("file,Speaker,speaker\na.pos,X,Y\n", r"columns 'Speaker' and 'speaker' both give the field 'speaker'"),
    ("file,2nd take\na.pos,X\n", r"column 2 \('2nd take'\): field name '2nd_take'"),
    ("file;state\na.pos;1\n", r"'state' is a column the tables already have"),
    ("filename\na.pos\n", r"has one column"),
    ("", r"is empty"),
])
def test_a_bad_table_is_refused_naming_the_line(tmp_path, text, message):
    with pytest.raises(MetadataError, match=message):
        read_metadata_table(_table(tmp_path, text))


def test_a_table_that_is_not_utf8_names_the_line(tmp_path):
    p = _table(tmp_path, "file;speaker\nä.pos;Jürgen\n", encoding="latin-1")
    with pytest.raises(MetadataError, match=r"line 2: byte 0xe4 is not UTF-8"):
        read_metadata_table(p)


def test_missing_and_extra_rows_are_warned_about_and_nothing_is_lost(tmp_path):
    p = _table(tmp_path, "recording,sex\nXYZFIA01,F\nQRSMNE01,M\n")
    paths = [str(tmp_path / "XYZFIA01.pos"), str(tmp_path / "XYZFIA02.pos")]
    fields, notes = assign_fields(paths, pattern=ISSUE_PATTERN, table=p)
    assert fields[paths[0]] == {"speaker": "XYZ", "sex": "F", "emotion": "IA", "text": "01"}
    assert fields[paths[1]]["speaker"] == "XYZ" and fields[paths[1]]["sex"] == "F"  # the pattern's sex stays
    assert any("no row for 1 of 2 inputs (XYZFIA02.pos)" in n for n in notes)
    assert any("1 row names no input (QRSMNE01; line 3)" in n for n in notes)


def test_a_table_naming_none_of_the_inputs_is_an_error(tmp_path):
    p = _table(tmp_path, "id,sex\nS1,F\nS2,M\n")
    with pytest.raises(MetadataError, match=r"no row names any of the 1 inputs \(column 'id' holds e.g. S1, S2"):
        assign_fields(["XYZFIA01.pos"], table=p)


def test_pattern_and_table_that_disagree_name_the_file_field_and_values(tmp_path):
    p = _table(tmp_path, "file,sex\nXYZFIA01.pos,M\n")
    with pytest.raises(MetadataError, match=r"XYZFIA01.pos: field 'sex' is 'F' by --fields-from but 'M' in .*line 2"):
        assign_fields(["XYZFIA01.pos"], pattern=ISSUE_PATTERN, table=p)


def test_fields_by_level_per_frame_and_per_utterance():
    f = [{"speaker": s, "emotion": e} for s in ("A", "B") for e in ("NE", "AN", "SA")]
    f[5] = {"speaker": "B"}  # one utterance without an emotion
    c = _corpus(6, f)
    assert field_names(c) == ["speaker", "emotion"]
    assert field_values(c, "emotion").tolist() == ["NE", "AN", "SA", "NE", "AN", ""]
    lv = field_levels(c, "emotion")
    assert [(a, n) for a, n, _ in lv] == [("AN", 2), ("NE", 2), ("SA", 1), ("", 1)]
    assert sum(fr for _, _, fr in lv) == c.n_frames
    codes, levels = frame_levels(c, "emotion")
    assert levels.tolist() == ["AN", "NE", "SA"] and codes.shape == (c.n_frames,)
    u5 = c.utterances[5]
    assert (codes[u5.start:u5.stop] == -1).all() and (levels[codes[:10]] == "NE").all()
    assert utterances_by_level(c, "speaker") == {"A": ["u0", "u1", "u2"], "B": ["u3", "u4", "u5"]}
    assert utterance_fields(c.utterances[0]) == {"speaker": "A", "emotion": "NE"}
    with pytest.raises(MetadataError, match=r"no utterance has a field 'group'; its fields: speaker, emotion"):
        require_field(c, "group")
    assert check_field_name("session") == "session"


def test_fields_survive_save_load_subset_concat_and_resample(tmp_path):
    from engine.io import concat, resample

    f = [{"speaker": "A", "sex": "F", "emotion": e} for e in ("NE", "AN", "SA")]
    c = _corpus(3, f)
    back = Corpus.load(c.save(tmp_path / "c.npz"))
    assert [utterance_fields(u) for u in back.utterances] == [utterance_fields(u) for u in c.utterances]
    assert field_values(c.subset(["u2"]), "emotion").tolist() == ["SA"]
    other = _corpus(1, [{"speaker": "B", "group": "patient"}])
    other = replace(other, utterances=[replace(other.utterances[0], id="v0")])
    j = concat([c, other])
    assert field_names(j) == ["speaker", "sex", "emotion", "group"]
    assert field_values(j, "group").tolist() == ["", "", "", "patient"]
    assert field_values(resample(j, 100.0), "emotion").tolist() == ["NE", "AN", "SA", ""]


def test_an_older_corpus_file_without_fields_loads_and_bad_field_arrays_name_the_file(tmp_path):
    c = _corpus(3, [{"speaker": "A", "sex": "F"}] * 3)
    d = c.to_arrays()
    old = {k: v for k, v in d.items() if not k.startswith("corpus_field_")}
    np.savez(tmp_path / "old.npz", **old)
    back = Corpus.load(tmp_path / "old.npz")
    assert field_names(back) == ["speaker"] and back.utterances[0].fields == ()
    bad = dict(d, corpus_field_values=np.array([["F"], ["F"]]))
    np.savez(tmp_path / "bad.npz", **bad)
    with pytest.raises(CorpusError, match=r"bad.npz: field 'corpus_field_values'"):
        Corpus.load(tmp_path / "bad.npz")


def test_a_manifold_knows_its_utterances_fields(tmp_path):
    from engine.manifold.model import Manifold
    from engine.talker.synthetic import load_synthetic

    c = load_synthetic(preset="small")
    emo = ["NE", "AN"]
    c = replace(c, utterances=[with_fields(u, {"speaker": f"S{k % 2}", "emotion": emo[k % 2]})
                               for k, u in enumerate(c.utterances)])
    m = Manifold(random_state=0).fit(c)
    back = Manifold.load(m.save(tmp_path / "m.npz"))
    assert field_values(back.corpus_, "emotion").tolist() == [emo[k % 2] for k in range(len(c.utterances))]
    assert field_values(back.corpus_, "speaker").tolist() == [f"S{k % 2}" for k in range(len(c.utterances))]

"""Per-utterance fields: what ``utterance_fields`` reads, and the one helper tests give corpora fields with."""
import numpy as np
import pytest

from engine.comparison.fields import (
    FieldError,
    attach_fields,
    describe_fields,
    field_values,
    level_counts,
    utterance_fields,
)
from engine.recordings.corpus import Corpus, Utterance


def _corpus(speakers, texts=None):
    n = len(speakers)
    texts = texts or [""] * n
    utts = [Utterance(f"u{i}", 3 * i, 3 * i + 3, (), None, t, s) for i, (s, t) in enumerate(zip(speakers, texts))]
    return Corpus(frames=np.zeros((3 * n, 6), np.float32), rate=60.0, utterances=utts, name="tiny")


def test_speaker_always_text_when_some_utterance_has_one():
    f = utterance_fields(_corpus(["A", "", "B"]))
    assert list(f) == ["speaker"]
    assert f["speaker"].tolist() == ["A", "", "B"]
    f = utterance_fields(_corpus(["A", "B"], ["one", " "]))
    assert f["text"].tolist() == ["one", ""]


def test_attached_fields_are_read_and_replace_the_attributes():
    c = attach_fields(_corpus(["A", "B"], ["x", "y"]), {"emotion": ["angry", "neutral"], "speaker": ["S1", "S1"]})
    f = utterance_fields(c)
    assert f["emotion"].tolist() == ["angry", "neutral"]
    assert f["speaker"].tolist() == ["S1", "S1"]  # a field of the corpus's metadata wins over Utterance.speaker
    assert f["text"].tolist() == ["x", "y"]


def test_fields_read_on_import_are_read_after_a_save(tmp_path):
    from dataclasses import replace

    from engine.recordings.metadata import with_fields

    c = _corpus(["A", "B"])
    c = replace(c, utterances=[with_fields(u, {"sex": sex}) for u, sex in zip(c.utterances, ("F", "M"))])
    c.save(tmp_path / "c.npz")
    f = utterance_fields(Corpus.load(tmp_path / "c.npz"))
    assert f["sex"].tolist() == ["F", "M"] and f["speaker"].tolist() == ["A", "B"]


def test_a_field_of_the_wrong_length_names_it():
    with pytest.raises(FieldError, match="'emotion' has 1 values; expected one value per utterance \\(2\\)"):
        attach_fields(_corpus(["A", "B"]), {"emotion": ["angry"]})


def test_levels_counts_and_messages():
    assert level_counts(["b", "a", "b", ""]) == {"b": 2, "a": 1}
    fields = {"speaker": np.array(["A", "B"]), "text": np.array(["t", "t"])}
    assert describe_fields(fields) == "speaker (2 levels), text (1 level)"
    with pytest.raises(FieldError, match="f.npz has no field 'emotion'; its fields: speaker \\(2 levels\\)"):
        field_values(fields, "emotion", source="f.npz")

"""Names kept at their old homes after a rename or a move still work, and warn (engine._deprecated)."""
from __future__ import annotations

import importlib

import pytest

#: (old module, old name, new module, new name)
MOVED = [
    ("engine.synthesis.viterbi", "ManifoldSynthesizer", "engine.synthesis.viterbi", "ViterbiSynthesizer"),
    ("engine.io.readers.ema", "write_est_track", "engine.io.writers.est_track", "write_est_track"),
    ("engine.io.readers.meshfile", "write_obj", "engine.io.writers.meshfile", "write_obj"),
    ("engine.io.readers.meshfile", "write_ply", "engine.io.writers.meshfile", "write_ply"),
    ("engine.io.readers.meshfile", "write_mesh", "engine.io.writers.meshfile", "write_mesh"),
    ("engine.io.readers.mview", "write_audio", "engine.io.writers.audio", "write_audio"),
]


@pytest.mark.parametrize(("old_module", "old", "new_module", "new"), MOVED)
def test_an_old_name_gives_the_new_object_with_a_deprecation_warning(old_module, old, new_module, new):
    module = importlib.import_module(old_module)
    with pytest.warns(DeprecationWarning, match=f"use {new_module}.{new}"):
        got = getattr(module, old)
    assert got is getattr(importlib.import_module(new_module), new)


def test_a_from_import_of_an_old_name_warns_and_other_names_still_fail():
    with pytest.warns(DeprecationWarning, match="ViterbiSynthesizer"):
        from engine.synthesis.viterbi import ManifoldSynthesizer  # noqa: F401
    with pytest.raises(AttributeError, match="no attribute 'NoSuchSynthesizer'"):
        importlib.import_module("engine.synthesis.viterbi").NoSuchSynthesizer  # noqa: B018


def test_the_old_talker_and_corpus_modules_still_give_every_public_name():
    """engine.talker.synthetic and engine.recordings.corpus gather the names of the modules they were split into."""
    from engine.recordings import corpus, corpus_format, utterances
    from engine.talker import gestures, synthetic, synthetic_talker, talker_cache

    for old, parts in ((synthetic, (gestures, synthetic_talker, talker_cache)), (corpus, (utterances,))):
        for part in parts:
            for name in part.__all__:
                if name in old.__all__:
                    assert getattr(old, name) is getattr(part, name), (old.__name__, name)
    assert corpus.FORMAT_VERSION == corpus_format.FORMAT_VERSION
    kept = {"load_synthetic", "SyntheticTalker", "gesture_phases", "cache_path", "PHONE_GESTURES"}
    assert kept <= set(synthetic.__all__)

"""The default talker at the first start: its corpus generated, the shipped fit put back on it, its speech
audio made in the background; the second start reads the corpus from the cache."""
from __future__ import annotations

from pathlib import Path

from app.files.source_loading import load_source, wait_for_background
from engine.phonetics.espeak_phones import espeak_library
from engine.phonetics.speech_audio import espeak_path
from engine.synthesis.method_choice import stored_choice

FIT_STAGES = {"shape space", "embedding", "tangent frames", "state graph"}


def test_first_and_second_start_of_the_default_talker(monkeypatch, tmp_path):
    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path))
    stages = []
    m, src = load_source(None, "default", lambda st, d, t: stages.append(st), prepare_views=False,
                         speech_audio="background")
    assert src["kind"] == "synthetic" and "loading the shipped manifold" in stages
    assert not FIT_STAGES & set(stages), "the shipped manifold is current: nothing is fitted"
    assert stored_choice(m) is not None  # the first synthesis needs no validation
    assert not (tmp_path / "manifolds").exists() or not any((tmp_path / "manifolds").iterdir())  # nothing to cache
    named = [u.audio for u in m.corpus_.utterances]
    assert wait_for_background(600)  # the corpus written to the cache, the audio made
    if espeak_library() or espeak_path():
        assert all(named)  # named at once, written in the background
        assert all(Path(p).is_file() for p in named) and "speech audio: espeak-ng" in m.corpus_.history[-1]
    else:
        assert "speech audio: none" in m.corpus_.history[-1]
    assert any(p.name.startswith("synthetic-default-") for p in tmp_path.glob("*.npz"))
    stages.clear()
    m2, _ = load_source(None, "default", lambda st, d, t: stages.append(st), prepare_views=False)
    assert {"loading cache", "loading the shipped manifold"} <= set(stages) and "articulation" not in stages
    assert not FIT_STAGES & set(stages) and m2.Fy_.shape == m.Fy_.shape

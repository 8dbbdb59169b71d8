"""A recording opened directly keeps its sound, kept in the cache (Qt-free)."""
from __future__ import annotations

from pathlib import Path

import pytest


def test_a_haskins_files_audio_is_extracted_once_into_the_cache_and_cleared_with_it(make_haskins_file, tmp_path,
                                                                                   monkeypatch):
    from app.files.cache import clear, entries
    from app.files.source_loading import read_recording

    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path / "cache"))
    path = make_haskins_file(tmp_path / "F01.mat", seconds=1.5)
    c = read_recording(path)
    wav = c.utterances[0].audio
    assert wav and wav.startswith(str(tmp_path / "cache" / "sound")) and wav.endswith("F01.wav")
    again = read_recording(path)                                                 # made once
    assert again.utterances[0].audio == wav
    assert [e.kind for e in entries(tmp_path / "cache")] == ["sound"]
    mine = tmp_path / "cache" / "sound" / "speech-0123456789abcdef.wav"  # the user's, named like an entry
    mine.write_bytes(b"the user's own file")
    clear(tmp_path / "cache")
    assert not Path(wav).parent.exists()                                         # Lipspace's own went
    assert [p.name for p in (tmp_path / "cache" / "sound").iterdir()] == [mine.name]  # the user's stayed
    assert mine.read_bytes() == b"the user's own file"
    silent = make_haskins_file(tmp_path / "F02.mat", seconds=1.0, audio=False)    # no AUDIO entry: silent, no error
    assert read_recording(silent).utterances[0].audio is None


def test_a_video_opened_directly_keeps_its_audio_track(tmp_path, monkeypatch):
    pytest.importorskip("mediapipe", reason="the [video] extra is not installed")
    skdata = pytest.importorskip("skimage.data", reason="scikit-image (the [video] extra) is not installed")
    import numpy as np

    from app.files.source_loading import read_recording
    from engine.io.video.synth import moving_image_frames, write_video

    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path / "cache"))
    img = np.ascontiguousarray(skdata.astronaut()[0:256, 96:352])
    n, rate, sr = 24, 30, 16000
    tone = 0.5 * np.sin(2 * np.pi * 440.0 * np.arange(int(n / rate * sr)) / sr)
    path = tmp_path / "talk.mp4"
    write_video(path, moving_image_frames(img, np.tile([0.0, 1.0, 0.0, 0.0], (n, 1))), rate, audio=tone, audio_rate=sr)
    c = read_recording(path)
    wav = c.utterances[0].audio
    assert wav and wav.startswith(str(tmp_path / "cache" / "sound"))
    import wave

    with wave.open(wav, "rb") as w:
        assert w.getframerate() == sr and abs(w.getnframes() - len(tone)) < sr * 0.05

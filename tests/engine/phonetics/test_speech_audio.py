"""Speech audio of the synthetic talker: pitch-keeping time stretch, words placed on their phones."""
from __future__ import annotations

import numpy as np
import pytest

from engine.phonetics import speech_audio as sa
from engine.phonetics.phones import PAUSE
from engine.recordings.corpus import PhoneInterval, Utterance
from engine.talker.synthetic import SyntheticTalker, load_synthetic

needs_espeak = pytest.mark.skipif(sa.espeak_path() is None, reason="espeak-ng is not installed")


def _peak_hz(x, sr=sa.SAMPLE_RATE):
    spec = np.abs(np.fft.rfft(x * np.hanning(len(x))))
    return np.fft.rfftfreq(len(x), 1 / sr)[np.argmax(spec)]


@pytest.mark.parametrize("factor", [0.6, 1.7])
def test_time_stretch_keeps_length_exact_and_pitch(factor):
    sr = sa.SAMPLE_RATE
    t = np.arange(int(0.5 * sr)) / sr
    x = (0.5 * np.sin(2 * np.pi * 200.0 * t)).astype(np.float32)
    n = int(len(x) * factor)
    y = sa.time_stretch(x, n)
    assert y.shape == (n,) and y.dtype == np.float32
    # resampling would move the pitch to 200 / factor Hz; WSOLA keeps it
    assert abs(_peak_hz(y) - 200.0) < 4.0
    assert 0.3 < np.sqrt(np.mean(y[sr // 20:-sr // 20] ** 2)) < 0.4  # no gaps or doubled windows


def test_word_spans_follow_the_phones():
    ph = (PhoneInterval(0.0, 0.2, PAUSE), PhoneInterval(0.2, 0.3, "hh"), PhoneInterval(0.3, 0.4, "ah"),
          PhoneInterval(0.4, 0.5, "t"), PhoneInterval(0.5, 0.8, PAUSE))
    u = Utterance("u1", 0, 48, ph, None, "Hut.")
    assert sa.word_spans(u) == [("hut", 0.2, 0.5)]
    with pytest.raises(ValueError, match="does not match its phones"):
        sa.word_spans(Utterance("u2", 0, 48, ph, None, "Hat."))


@needs_espeak
def test_utterance_audio_speaks_the_words_in_their_spans_and_is_silent_in_pauses():
    c = SyntheticTalker(preset="small", n_sentences=3, seed=2).generate()
    for u in c.utterances:
        x, info = sa.utterance_audio(u, method="words")  # the fallback without espeak-ng's library
        sr = sa.SAMPLE_RATE
        assert len(x) == int(round(u.phones[-1].end * sr))
        assert info["split"] and info["words"] == len(u.text.split())

        def rms(a, b, x=x, sr=sr):
            return float(np.sqrt(np.mean(x[int(a * sr):int(b * sr)] ** 2)))

        level = rms(0, len(x) / sr)
        first, last = u.phones[0], u.phones[-1]
        assert rms(first.start, first.end) < 0.01 * level and rms(last.start, last.end) < 0.01 * level
        for _, s, e in sa.word_spans(u):
            assert rms(s, e) > 0.2 * level


@needs_espeak
def test_load_synthetic_with_audio_gives_every_utterance_a_wav(tmp_path):
    from app.audio import resolve_audio_path

    c = load_synthetic(preset="small", n_sentences=2, cache_dir=tmp_path, audio=True)
    for u in c.utterances:
        p = resolve_audio_path(u.audio)
        assert p is not None
        x, sr = sa.read_wav(p)
        assert sr == sa.SAMPLE_RATE and abs(len(x) / sr - u.n_frames / c.rate) < 1.0 / c.rate
    again = load_synthetic(preset="small", n_sentences=2, cache_dir=tmp_path, audio=True)  # files reused
    assert [u.audio for u in again.utterances] == [u.audio for u in c.utterances]


def test_without_espeak_the_corpus_says_why(tmp_path, monkeypatch):
    monkeypatch.setattr(sa, "espeak_path", lambda: None)
    monkeypatch.setattr(sa.espeak_phones, "espeak_library", lambda: None)
    c = load_synthetic(preset="small", n_sentences=2, cache_dir=tmp_path, audio=True)
    assert all(u.audio is None for u in c.utterances)
    assert any("espeak-ng is not installed" in h for h in c.history)
    with pytest.raises(sa.SpeechAudioUnavailable, match="apt-get install espeak-ng"):
        sa.add_speech_audio(c, tmp_path / "wav")

"""Audio for the exports: a non-WAV recording becomes the WAV beside the .glb; odd sample rates still mux."""
import wave

import numpy as np
import pytest

av = pytest.importorskip("av")


def _tone(rate, seconds=0.4, freq=300.0):
    t = np.arange(int(seconds * rate)) / rate
    return (0.4 * np.sin(2 * np.pi * freq * t)).astype(np.float32)


def _write_flac(path, x, rate):
    with av.open(str(path), "w") as out:
        s = out.add_stream("flac", rate=rate)
        s.layout = "mono"
        f = av.AudioFrame.from_ndarray(x[None], format="fltp", layout="mono")
        f.sample_rate = rate
        out.mux(s.encode(f))
        out.mux(s.encode(None))
    return path


def test_non_wav_audio_is_decoded_to_a_16_bit_wav_beside(tmp_path):
    from app.export.animation import write_audio_beside

    x = _tone(22050)
    src = _write_flac(tmp_path / "voice.flac", x, 22050)
    dst = write_audio_beside(src, tmp_path / "speech.wav")
    with wave.open(str(dst)) as w:
        assert (w.getframerate(), w.getnchannels(), w.getsampwidth()) == (22050, 1, 2)
        y = np.frombuffer(w.readframes(w.getnframes()), np.int16) / 32767
    assert len(y) == len(x)
    np.testing.assert_allclose(y, x, atol=2e-3)  # FLAC is lossless; 16-bit rounding remains
    with pytest.raises(FileNotFoundError, match="no such audio file"):
        write_audio_beside(tmp_path / "none.flac", tmp_path / "x.wav")
    assert not (tmp_path / "x.wav").exists()


def test_decode_resamples_and_rejects_files_without_audio(tmp_path):
    from app.export.video import AAC_RATES, decode_audio

    src = _write_flac(tmp_path / "odd.flac", _tone(12345), 12345)
    assert 12345 not in AAC_RATES
    x, rate = decode_audio(src, rate=48000)
    assert rate == 48000 and x.shape[0] == 1 and abs(x.shape[1] - round(0.4 * 48000)) < 200
    (tmp_path / "text.wav").write_text("not audio")
    with pytest.raises(ValueError, match="text.wav: cannot read audio"):
        decode_audio(tmp_path / "text.wav")


@pytest.mark.gui
def test_mp4_with_audio_at_a_rate_aac_lacks(tmp_path):
    from app.export.video import render_video

    src = _write_flac(tmp_path / "odd.flac", _tone(12345), 12345)
    frames = np.random.default_rng(0).normal(size=(12, 3 * 5))
    p = render_video(tmp_path / "odd.mp4", frames, rate=30.0, audio=src, size=(64, 48))
    with av.open(str(p)) as f:
        assert f.streams.audio[0].codec_context.sample_rate == 48000
        assert sum(1 for _ in f.decode(video=0)) == 12

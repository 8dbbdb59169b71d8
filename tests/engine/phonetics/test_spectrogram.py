"""The spectrogram under the editor's timeline: Praat's numbers, its grey levels, the waveform envelope, WAV reading."""
from __future__ import annotations

import wave

import numpy as np
import pytest

from engine.phonetics.spectrogram import read_sound, sound_display, spectrogram, waveform_envelope


def _speechlike(sr, seconds=1.2, seed=0):
    """A sound with silence, a harmonic vowel-like part, a noise burst and a click: every kind of cell."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * sr)) / sr
    x = np.zeros_like(t)
    v = (t > 0.2) & (t < 0.7)
    for k in range(1, 30):  # 120 Hz harmonics with a formant-like envelope
        f = 120.0 * k
        if f < 0.45 * sr:
            x[v] += np.exp(-((f - 700) / 300) ** 2 - 0.2 * k / 10) * np.sin(2 * np.pi * f * t[v])
    n = (t > 0.8) & (t < 1.0)
    x[n] += 0.3 * rng.standard_normal(int(n.sum()))
    x[int(1.1 * sr)] = 0.9
    return (0.5 * x / np.abs(x).max()).astype(np.float32)


def _write_wav(path, x, sr, width=2, channels=1):
    a = np.asarray(x, np.float64)
    if channels > 1:
        a = np.repeat(a[:, None], channels, axis=1)
    if width == 1:
        data = np.clip(np.rint(a * 127 + 128), 0, 255).astype(np.uint8)
    elif width == 2:
        data = np.clip(np.rint(a * 32767), -32768, 32767).astype("<i2")
    else:  # 24-bit
        i = np.clip(np.rint(a * (2 ** 23 - 1)), -(2 ** 23), 2 ** 23 - 1).astype("<i4")
        data = np.frombuffer(i.tobytes(), np.uint8).reshape(-1, 4)[:, :3].copy()
    with wave.open(str(path), "wb") as w:
        w.setnchannels(channels)
        w.setsampwidth(width)
        w.setframerate(sr)
        w.writeframes(data.tobytes())
    return path


@pytest.mark.parametrize("sr, window, fmax, df", [(16000, 0.005, 8000, 20), (22050, 0.005, 8000, 20),
                                                   (44100, 0.005, 8000, 20), (16000, 0.005, 5000, 200),
                                                   (11025, 0.03, 8000, 20)])
def test_the_values_are_praats_to_spectrogram(tmp_path, praat, sr, window, fmax, df):
    """Frame times, band centres and every cell in dB as Praat's Sound: To Spectrogram (Gaussian) gives them
    (wide and narrow band; a Nyquist below 8 kHz; bands of several FFT bins)."""
    x = _speechlike(sr)
    wav = _write_wav(tmp_path / "s.wav", x, sr)
    out = tmp_path / "praat.tsv"
    info = praat("form Spectrogram\n  sentence wav x\n  sentence out y\n  real window 0.005\n  real fmax 8000\n"
                 "  real df 20\nendform\nRead from file: wav$\n"
                 'To Spectrogram: window, fmax, 0.002, df, "Gaussian"\nm = To Matrix\n'
                 "x1 = Get x of column: 1\ndx = Get column distance\ny1 = Get y of row: 1\ndy = Get row distance\n"
                 'writeInfoLine: fixed$ (x1, 12), " ", fixed$ (dx, 12), " ", fixed$ (y1, 12), " ", fixed$ (dy, 12)\n'
                 "Save as headerless spreadsheet file: out$\n", wav, out, window, fmax, df)
    x1, dx, y1, dy = (float(v) for v in info.split())
    P = np.loadtxt(out, ndmin=2)
    s = spectrogram(read_sound(wav)[0], sr, window_length=window, max_frequency=fmax, frequency_step=df)
    assert s.power_db.shape == P.shape
    assert s.times[0] == pytest.approx(x1, abs=1e-9) and s.time_step == pytest.approx(dx, rel=1e-9)
    assert s.frequencies[0] == pytest.approx(y1, abs=1e-6) and s.frequency_step == pytest.approx(dy, rel=1e-9)
    loud = P > P.max() * 1e-9  # Praat's float64 against our float32: compare above -90 dB re the maximum
    d = np.abs(10 * np.log10(P[loud] / 4e-10) - s.power_db[loud])
    assert d.max() < 0.05, f"largest difference {d.max():.3f} dB"


def test_a_tone_and_a_click_land_where_they_are(tmp_path):
    """Without Praat: a 1 kHz tone fills the 1 kHz band of its frames and nothing else; a click's frame is
    the one centred on it; frames are centred in the sound."""
    sr = 16000
    t = np.arange(sr) / sr
    x = np.where(t < 0.5, np.sin(2 * np.pi * 1000 * t), 0.0).astype(np.float32)
    x[int(0.75 * sr)] = 1.0
    s = spectrogram(x, sr)
    assert s.times[0] - 0.0 == pytest.approx(1.0 - s.times[-1], abs=1e-9)
    tone = s.times < 0.45
    band = np.argmax(s.power_db[:, tone], axis=0)
    assert np.all(np.abs(s.frequencies[band] - 1000) <= s.frequency_step)
    near = np.abs(s.frequencies - 1000) > 500
    assert np.median(s.power_db[near][:, tone]) < np.median(s.power_db[~near][:, tone]) - 40
    k = int(np.argmax(s.power_db[:, s.times > 0.6].sum(axis=0))) + int(np.sum(s.times <= 0.6))
    assert abs(s.times[k] - 0.75) <= s.time_step
    assert s.frequencies[-1] < 8000 <= s.frequencies[-1] + s.frequency_step


def test_grey_levels_black_at_the_top_white_50_db_below_with_pre_emphasis():
    from engine.phonetics.spectrogram import Spectrogram

    f = np.array([500.0, 1000.0, 2000.0, 4000.0])
    db = np.array([[60.0, 10.0], [60.0, 30.0], [60.0, 60.0], [60.0, 90.0]], np.float32)
    s = Spectrogram(times=np.array([0.1, 0.2]), frequencies=f, power_db=db, time_step=0.1, window_length=0.005,
                    frequency_step=500.0, max_frequency=4500.0)
    flat = s.grey(preemphasis=0.0)
    assert flat[3, 1] == 0 and flat[0, 1] == 255  # 90 dB is the maximum; 10 dB is 80 below: white
    assert flat[2, 1] == round(255 * 30 / 50) and flat[0, 0] == round(255 * 30 / 50)
    g = s.grey()  # +6 dB per octave about 1 kHz: 4 kHz lifted 12 dB, 500 Hz lowered 6
    assert g[3, 1] == 0 and g[0, 0] > g[1, 0] > g[2, 0] > g[3, 0]
    assert g[1, 0] - g[2, 0] == pytest.approx(255 * 6 / 50, abs=1)
    assert s.grey(dynamic_range=100.0, preemphasis=0.0)[0, 1] == round(255 * 80 / 100)
    with pytest.raises(ValueError, match="dynamic_range"):
        s.grey(dynamic_range=0)


def test_waveform_envelope_is_the_min_and_max_of_each_bin():
    x = np.random.default_rng(1).standard_normal(1000).astype(np.float32)
    edges = np.array([-5, 0, 10, 10, 250, 999, 1000, 1200])
    lo, hi = waveform_envelope(x, edges)
    e = np.clip(edges, 0, 1000)
    for j in range(len(e) - 1):
        seg = x[e[j]:e[j + 1]]
        if seg.size:
            assert lo[j] == seg.min() and hi[j] == seg.max()
        else:  # an empty bin is the sample at its start
            assert lo[j] == hi[j] == x[min(e[j], 999)]
    with pytest.raises(ValueError, match="increasing"):
        waveform_envelope(x, [5, 3])


@pytest.mark.parametrize("width, channels", [(1, 1), (2, 2), (3, 1)])
def test_read_sound_reads_8_16_24_bit_and_averages_channels(tmp_path, width, channels):
    sr = 8000
    x = 0.5 * np.sin(2 * np.pi * 440 * np.arange(800) / sr)
    y, rate = read_sound(_write_wav(tmp_path / "a.wav", x, sr, width, channels))
    assert rate == sr and y.dtype == np.float32 and y.shape == (800,)
    np.testing.assert_allclose(y, x, atol={1: 0.01, 2: 1e-4, 3: 1e-6}[width])


def test_a_file_that_is_no_wav_is_refused_by_name(tmp_path):
    bad = tmp_path / "speech.wav"
    bad.write_text("not a wave file")
    with pytest.raises(ValueError, match="speech.wav.*WAV"):
        read_sound(bad)
    d = sound_display(_write_wav(tmp_path / "ok.wav", _speechlike(16000), 16000))
    assert d.duration == pytest.approx(1.2) and d.spectrogram.power_db.shape[0] == 256

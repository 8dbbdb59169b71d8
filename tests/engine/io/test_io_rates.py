"""Resampling per utterance with anti-aliasing; joining corpora."""
import numpy as np
import pytest

from engine.io import concat, resample
from engine.recordings.corpus import Corpus, CorpusError, PhoneInterval, Utterance


def _corpus(signals, rate, *, latent=None, phones=None):
    """One utterance per 1-D signal; each frame has two 2-D points built from the signal."""
    utts, pos = [], 0
    for k, s in enumerate(signals):
        utts.append(Utterance(f"u{k}", pos, pos + len(s), tuple((phones or {}).get(k, ()))))
        pos += len(s)
    x = np.concatenate(signals)
    F = np.column_stack([x, 2 * x, -x, np.ones_like(x)])
    return Corpus(frames=F, rate=rate, utterances=utts, dims=2, latent=latent or {}, name="t")


@pytest.mark.parametrize("new", [60.0, 59.94, 100.0, 1000.0])
def test_low_frequencies_pass(new):
    old, f = 500.0, 2.0
    t = np.arange(1000) / old
    c = _corpus([np.sin(2 * np.pi * f * t)], old)
    r = resample(c, new)
    assert r.rate == new and r.n_frames == int(np.ceil(1000 * new / old - 1e-9))
    tn = np.arange(r.n_frames) / new
    err = np.abs(r.frames[:, 0] - np.sin(2 * np.pi * f * tn))
    inner = (tn > 0.1) & (tn < t[-1] - 0.1)
    assert err[inner].max() < 0.01 and err.max() < 0.1
    np.testing.assert_allclose(r.frames[:, 1], 2 * r.frames[:, 0], atol=1e-5)
    np.testing.assert_allclose(r.frames[:, 3], 1.0, atol=1e-3)


@pytest.mark.parametrize("new", [60.0, 59.94])
def test_frequencies_above_the_new_nyquist_are_removed(new):
    old = 500.0
    t = np.arange(2000) / old
    c = _corpus([np.sin(2 * np.pi * 40.0 * t)], old)  # 40 Hz would alias to ~20 Hz at 60 Hz
    r = resample(c, new)
    inner = slice(int(0.2 * new), r.n_frames - int(0.2 * new))
    assert np.abs(r.frames[inner, 0]).max() < 0.05
    naive = c.frames[np.round(np.arange(r.n_frames) * old / new).astype(int).clip(0, 1999), 0]
    assert np.abs(naive[inner]).max() > 0.5  # plain decimation would alias


def test_utterances_stay_apart_and_phones_keep_their_times():
    a, b = np.zeros(333), np.full(250, 100.0)
    phones = {0: [PhoneInterval(0.1, 0.3, "m"), PhoneInterval(0.3, 0.666, "a")], 1: [PhoneInterval(0.0, 0.5, "p")]}
    lat = {"aperture": np.concatenate([np.linspace(0, 1, 333), np.linspace(1, 0, 250)]),
           "phone_id": np.repeat([1, 2], [333, 250])}
    c = _corpus([a, b], 500.0, latent=lat, phones=phones)
    r = resample(c, 60.0)
    n0 = int(np.ceil(333 * 60 / 500))
    assert r.bounds.tolist() == [[0, n0], [n0, n0 + int(np.ceil(250 * 60 / 500))]]
    assert np.abs(r.frames[:n0, 0]).max() < 1e-6  # nothing leaks across the bound
    np.testing.assert_allclose(r.frames[n0:, 0], 100.0, atol=1e-3)
    assert r.utterances[0].phones == c.utterances[0].phones and r.utterances[1].phones == c.utterances[1].phones
    assert r.latent["phone_id"].dtype == lat["phone_id"].dtype
    assert set(r.latent["phone_id"][:n0]) == {1} and set(r.latent["phone_id"][n0:]) == {2}
    ta = np.arange(n0) / 60.0
    np.testing.assert_allclose(r.latent["aperture"][5:n0 - 5], (ta * 500 / 332)[5:n0 - 5], atol=0.01)
    assert c.rate == 500.0 and c.n_frames == 583  # input untouched


def test_same_rate_and_bad_rates():
    c = _corpus([np.arange(10.0)], 100.0)
    r = resample(c, 100.0)
    np.testing.assert_array_equal(r.frames, c.frames)
    assert r.frames is not c.frames
    for bad in (0, -5, float("nan")):
        with pytest.raises(CorpusError, match="positive rate"):
            resample(c, bad)
    with pytest.raises(CorpusError, match="at least 2"):
        resample(_corpus([np.arange(3.0)], 100.0), 1.0)


def test_concat_checks():
    a = _corpus([np.zeros(10)], 100.0)
    b = _corpus([np.ones(12)], 100.0)
    b.utterances[0] = Utterance("v0", 0, 12)
    ab = concat([a, b])
    assert ab.n_frames == 22 and [u.id for u in ab.utterances] == ["u0", "v0"]
    with pytest.raises(CorpusError, match="at 50 Hz but corpus 0 .* at 100 Hz; corpora can be joined only at one "
                                          "frame rate: resample"):
        concat([a, _corpus([np.zeros(5)], 50.0)])
    with pytest.raises(CorpusError, match="no corpora"):
        concat([])

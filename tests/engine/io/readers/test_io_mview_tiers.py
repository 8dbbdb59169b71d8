"""Haskins / MVIEW .mat files made as the IEEE files are: the word tier and the AUDIO entry are kept."""
from __future__ import annotations

import pytest

from engine.io import read_corpus, read_mview_audio
from engine.recordings.corpus import Corpus


def test_the_word_tier_is_read_kept_through_resampling_and_saved(make_haskins_file, tmp_path):
    from engine.io import resample

    path = make_haskins_file(tmp_path / "F09_B01_S01_R01_N.mat", seconds=2.0)
    c = read_corpus(path)
    u = c.utterances[0]
    assert [w.label for w in u.words] == ["sp", "BOB", "MEETS", "MUM", "sp"]
    assert u.words[1].start == pytest.approx(0.4) and u.words[-1].end == pytest.approx(2.0)
    assert [p.label for p in u.phones][:4] == ["sp", "B", "AA1", "B"]
    r = resample(c, 60.0)
    assert r.utterances[0].words == u.words                        # seconds: the same at any rate
    c.save(tmp_path / "c.npz")
    assert Corpus.load(tmp_path / "c.npz").utterances[0].words == u.words
    x, sr = read_mview_audio(path)
    assert sr == 44100.0 and x.shape == (88200,)


def test_a_file_without_words_reads_as_before(make_haskins_file, tmp_path):
    import scipy.io

    path = make_haskins_file(tmp_path / "M02.mat", seconds=1.0)
    m = scipy.io.loadmat(path)
    s = m["M02"]
    s = s[:, :]  # the same struct without its WORDS field
    import numpy as np

    dt = [(n, "O") for n in s.dtype.names if n != "WORDS"]
    t = np.zeros(s.shape, dtype=dt)
    for n, _ in dt:
        t[n] = s[n]
    scipy.io.savemat(path, {"M02": t})
    c = read_corpus(path)
    assert c.utterances[0].words == () and len(c.utterances[0].phones) > 0
    c.save(tmp_path / "c.npz")
    assert Corpus.load(tmp_path / "c.npz").utterances[0].words == ()

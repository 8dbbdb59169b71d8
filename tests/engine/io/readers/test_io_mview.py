"""Haskins / MVIEW .mat EMA: the two real IEEE sample utterances."""
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from engine.io import ImportFormatError, concat, read_corpus, read_mview, read_mview_audio, write_audio
from engine.recordings.corpus import CorpusError


def _repo_root():
    p = Path(__file__).resolve()
    while not (p / "pyproject.toml").exists():
        p = p.parent
    return p


HASKINS = _repo_root().parent / "shared" / "data" / "haskins-ieee"
FILES = sorted(HASKINS.glob("*.mat"))
pytestmark = pytest.mark.skipif(len(FILES) < 2, reason=f"Haskins sample not found at {HASKINS} (../shared/data)")

BILABIAL = {"M", "P", "B"}
OPEN_VOWELS = {"AA", "AE", "AO", "AH"}


@pytest.fixture(scope="module")
def corpora():
    return [read_mview(f) for f in FILES]


def test_both_files_load_as_3d_lip_corpora(corpora):
    for f, c in zip(FILES, corpora):
        u = c.utterances[0]
        assert c.rate == 100.0 and c.dims == 3 and c.point_names == ["UL", "LL", "ML", "JAW", "JAWL"]
        assert c.frames.shape == (c.n_frames, 15) and c.frames.dtype == np.float32
        assert u.id == f.stem and u.text == "The birch canoe slid on the smooth planks."
        raw = scipy.io.loadmat(f)[f.stem][0]
        ul = next(e for e in raw if str(e["NAME"][0]) == "UL")["SIGNAL"]
        np.testing.assert_array_equal(c.frames[:, :3], ul[:, :3])
        assert len(u.phones) == np.asarray(raw[0]["PHONES"]).size  # nothing dropped
        labels = [p.label for p in u.phones]
        assert labels[0] == "sp" and "ER1" in labels and "UW1" in labels  # ARPAbet with stress, kept as given


def test_frames_cover_the_phones(corpora):
    for c in corpora:
        u = c.utterances[0]
        assert c.n_frames / c.rate >= u.phones[-1].end  # frames x 1/100 s reach the last phone end
        assert u.phones[-1].end > c.n_frames / c.rate - 0.05  # ... and the alignment spans the recording
        mids, labels, _, st, en = c.phone_table()
        assert (st <= mids).all() and (mids <= en).all() and en.max() < c.n_frames


def test_lips_close_for_bilabials(corpora):
    """Real data: UL-LL vertical distance is small in /m p b/ (closure) and large in open vowels."""
    for c in corpora:
        u = c.utterances[0]
        P = c.frames.reshape(c.n_frames, -1, 3)
        gap = P[:, 0, 2] - P[:, 1, 2]  # z is vertical
        closed, open_ = [], []
        for p in u.phones:
            a, b = c.time_to_frame(u, p.start), c.time_to_frame(u, p.end)
            seg = gap[a:b + 1]
            if p.label in BILABIAL:
                closed.append(seg.min())
            elif p.label.rstrip("012") in OPEN_VOWELS and p.label[-1] == "1":
                open_.append(seg.max())
        assert len(closed) >= 3 and len(open_) >= 2
        assert max(closed) + 5.0 < min(open_), (closed, open_)  # at least 5 mm apart


def test_the_two_files_concatenate(corpora):
    both = concat(corpora)
    assert both.n_frames == sum(c.n_frames for c in corpora)
    assert [u.id for u in both.utterances] == [f.stem for f in FILES]
    assert both.bounds.tolist() == [[0, corpora[0].n_frames], [corpora[0].n_frames, both.n_frames]]
    np.testing.assert_array_equal(both.frames[corpora[0].n_frames:], corpora[1].frames)
    via = read_corpus(FILES)
    np.testing.assert_array_equal(via.frames, both.frames)
    with pytest.raises(CorpusError, match="repeats utterance id"):
        concat([corpora[0], corpora[0]])
    with pytest.raises(CorpusError, match="has 3 points in 3-D but corpus 0"):
        concat([corpora[0], read_mview(FILES[1], sensors=("UL", "LL", "JAW"))])


def test_sensor_choice_and_errors(tmp_path):
    c = read_mview(FILES[0], sensors="all")
    assert c.n_points == 8 and "TT" in c.point_names
    with pytest.raises(ImportFormatError, match=r"no sensor entries \['NOSE'\]"):
        read_mview(FILES[0], sensors=("UL", "NOSE"))
    bad = tmp_path / "x.mat"
    bad.write_bytes(b"not a mat file at all")
    with pytest.raises(ImportFormatError, match="expected a MATLAB 5 MAT-file"):
        read_mview(bad)
    other = tmp_path / "y.mat"
    scipy.io.savemat(other, {"y": np.zeros((3, 3))})
    with pytest.raises(ImportFormatError, match="MVIEW struct array"):
        read_mview(other)


def test_audio_is_written_atomically_and_linked(tmp_path):
    x, r = read_mview_audio(FILES[0])
    assert r == 44100.0 and x.shape[0] > 100000
    wav = write_audio(FILES[0], tmp_path / "a.wav")
    rr, y = scipy.io.wavfile.read(wav)
    assert rr == 44100 and y.dtype == np.int16 and y.shape == x.shape
    np.testing.assert_allclose(y / 32767, x, atol=1.0 / 32767)
    assert list(tmp_path.iterdir()) == [wav]  # no temporary file left
    # the audio runs as long as the articulography (2.6 s at 44.1 kHz vs frames at 100 Hz)
    c = read_mview(FILES[0])
    assert abs(x.shape[0] / r - c.n_frames / c.rate) < 0.05

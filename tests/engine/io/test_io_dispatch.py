"""read_corpus: choosing the reader by extension or content; options; several files."""
import re
import shutil

import numpy as np
import pytest

from engine.io import ImportFormatError, detect_format, read_corpus, write_est_track, write_obj, write_trajectory_csv
from engine.recordings.corpus import Corpus, CorpusError, PhoneInterval, Utterance


def _est(path):
    t = np.arange(50) / 500.0
    v = np.random.default_rng(0).normal(size=(50, 4)) * 100
    return write_est_track(path, t, v, ["ul_x", "ul_y", "ll_x", "ll_y"])


def test_format_by_extension_and_by_content(tmp_path):
    assert detect_format(tmp_path / "a.ema") == "ema"
    assert detect_format(tmp_path / "a.MAT") == "mview"
    assert detect_format(str(tmp_path / "frames" / "*.ply")) == "mesh"
    assert detect_format(tmp_path) == "mesh"
    blob = _est(tmp_path / "track.bin")  # EST header, unknown extension
    assert detect_format(blob) == "ema"
    c = read_corpus(blob, sensors=("UL", "LL"), alignment=False)
    assert c.rate == 500 and c.point_names == ["UL", "LL"]
    np.save(tmp_path / "v.npy", np.zeros((3, 2, 3)))
    shutil.copy(tmp_path / "v.npy", tmp_path / "v.data")
    assert detect_format(tmp_path / "v.data") == "npy"
    (tmp_path / "x.data").write_bytes(b"\x00\x01\x02 nothing known")
    with pytest.raises(ImportFormatError, match="cannot tell the format"):
        read_corpus(tmp_path / "x.data")


def test_alignment_files_and_unknown_formats_and_options(tmp_path):
    (tmp_path / "a.TextGrid").write_text("x")
    with pytest.raises(ImportFormatError, match="is a phone alignment, not lip data"):
        read_corpus(tmp_path / "a.TextGrid")
    e = _est(tmp_path / "e.ema")
    with pytest.raises(ValueError, match="format='wav' is not known"):
        read_corpus(e, format="wav")
    with pytest.raises(TypeError, match=r"format 'ema' takes no option\(s\) \['markers'\]; it takes .*sensors"):
        read_corpus(e, markers=["A"])
    assert read_corpus(e, format="mocha", sensors=["ul"]).n_points == 1
    with pytest.raises(FileNotFoundError):
        read_corpus(tmp_path / "missing.ema")


def test_native_npz_with_an_alignment(tmp_path):
    c = Corpus(frames=np.random.default_rng(1).normal(size=(100, 6)), rate=100, utterances=[Utterance("u", 0, 100)])
    p = c.save(tmp_path / "c.npz")
    lab = tmp_path / "u.lab"
    lab.write_text("0 0.5 a\n0.5 1.5 b\n")  # runs past the 1 s of data: cut
    r = read_corpus(p, alignment=lab)
    assert [h for h in r.history if re.search(r"c\.npz: the alignment runs to 1\.500 s but the data last "
                                              r"1\.000 s .*cut", h)], r.history  # kept in the corpus history
    assert [(x.start, x.end, x.label) for x in r.utterances[0].phones] == [(0, 0.5, "a"), (0.5, 1.0, "b")]
    np.testing.assert_array_equal(r.frames, c.frames)
    with pytest.raises(ImportFormatError, match="100 Hz but a rate of 60 Hz"):
        read_corpus(p, rate=60)


def test_several_files_become_utterances(tmp_path):
    X = np.random.default_rng(2).normal(size=(30, 4))
    a = write_trajectory_csv(tmp_path / "a.csv", X, rate=50, columns=["p_x", "p_y", "q_x", "q_y"])
    b = write_trajectory_csv(tmp_path / "b.csv", X[:20], rate=50, columns=["p_x", "p_y", "q_x", "q_y"])
    (tmp_path / "b.lab").write_text("0 0.2 m\n")  # found beside b.csv
    c = read_corpus([a, b])
    assert [u.id for u in c.utterances] == ["a", "b"] and c.bounds.tolist() == [[0, 30], [30, 50]]
    assert c.utterances[0].phones == () and [p.label for p in c.utterances[1].phones] == ["m"]
    with pytest.raises(ValueError, match="one alignment file for 2 inputs"):
        read_corpus([a, b], alignment=tmp_path / "b.lab")
    # a list of mesh files is one sequence, not several utterances
    for k in range(3):
        write_obj(tmp_path / f"m{k}.obj", np.eye(3) * k)
    m = read_corpus([tmp_path / f"m{k}.obj" for k in range(3)], rate=10)
    assert m.n_frames == 3 and len(m.utterances) == 1


def test_native_npz_with_phones_out_of_range_is_refused_not_dropped(tmp_path):
    """A phone outside its utterance, or of an utterance that does not exist: the file, the phone and the range."""
    from engine.files.persist import read_npz

    c = Corpus(frames=np.zeros((100, 6)), rate=100, utterances=[Utterance("u", 0, 100, (PhoneInterval(0, 0.5, "a"),))])
    d = read_npz(c.save(tmp_path / "c.npz"))
    for name, key, value, says in [
        ("late.npz", "corpus_phone_times", np.array([[5.0, 6.0]]), r"late\.npz: .*phone 0 \('a' 5\.0000-6\.0000 s\): "
                                                                     r"lies outside the utterance \(0-1\.0000 s"),
        ("utt.npz", "corpus_phone_utt", np.array([3]), r"utt\.npz: field 'corpus_phone_utt': value 3 is out of range "
                                                       r"\(must be < 1\)"),
    ]:
        with open(tmp_path / name, "wb") as fh:
            np.savez(fh, **{**d, key: value})
        with pytest.raises(CorpusError, match=says):
            read_corpus(tmp_path / name)

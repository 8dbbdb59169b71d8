"""Readers that said nothing where they guessed (issue 45, classes 7 and 9): a TextGrid is read as Praat
reads it (labels over two lines, double quotes, every tier), a tier before 0 s or two tiers of one name are
refused, two alignments beside the input are said, a .wav beside it is checked, an MVIEW SRATE must be one
number and a .mat one MVIEW struct."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.io

from engine.io import ImportFormatError, read_corpus, read_textgrid
from engine.io.readers.mview import read_mview

HEAD = 'File type = "ooTextFile"\nObject class = "TextGrid"\n\nxmin = {xmin}\nxmax = 0.6\ntiers? <exists>\nsize = {n}\n'
TIER = ('item [{k}]:\n    class = "IntervalTier"\n    name = "{name}"\n    xmin = {xmin}\n    xmax = 0.6\n'
        '    intervals: size = 2\n    intervals [1]:\n        xmin = {xmin}\n        xmax = 0.3\n'
        '        text = {first}\n'
        '    intervals [2]:\n        xmin = 0.3\n        xmax = 0.6\n        text = "aa"\n')


def _tg(path, names=("phones",), xmin=0, first='"p"'):
    path.write_text(HEAD.format(xmin=xmin, n=len(names)) + "item []:\n" +
                    "".join(TIER.format(k=k + 1, name=n, xmin=xmin, first=first) for k, n in enumerate(names)))
    return path


def _csv(path):
    path.write_text("time,UL_x,UL_y,LL_x,LL_y\n" + "".join(f"{k / 100:.2f},{np.sin(k / 7):.4f},2,{k % 5},-3\n"
                                                           for k in range(60)))
    return path


def test_labels_over_two_lines_and_double_quotes_are_read_as_praat_reads_them(tmp_path):
    assert [p.label for p in read_textgrid(_tg(tmp_path / "a.TextGrid", first='"p\nb"'))] == ["p b", "aa"]
    assert [p.label for p in read_textgrid(_tg(tmp_path / "q.TextGrid", first='"say ""hi"""'))] == ['say "hi"', "aa"]
    short = tmp_path / "s.TextGrid"
    short.write_text('File type = "ooTextFile short"\n"TextGrid"\n\n0\n0.6\n<exists>\n1\n"IntervalTier"\n"phones"\n'
                     '0\n0.6\n2\n0\n0.3\n"m\ne"\n0.3\n0.6\n"aa"\n')
    assert [p.label for p in read_textgrid(short)] == ["m e", "aa"]
    bad = tmp_path / "u.TextGrid"
    bad.write_text(_tg(tmp_path / "x.TextGrid").read_text().replace('text = "p"', 'text = "p'))
    with pytest.raises(ImportFormatError, match="never closed|the file ends"):
        read_textgrid(bad)


def test_two_tiers_of_one_name_and_a_tier_before_zero_are_refused(tmp_path):
    with pytest.raises(ImportFormatError, match="tiers 1 and 3 are both named 'phones'"):
        read_textgrid(_tg(tmp_path / "d.TextGrid", names=("phones", "words", "phones")))
    with pytest.raises(ImportFormatError, match="before the recording starts"):
        read_textgrid(_tg(tmp_path / "n.TextGrid", xmin=-0.5))
    assert [p.label for p in read_textgrid(_tg(tmp_path / "w.TextGrid", names=("phones", "words", "words")))] == \
        ["p", "aa"]  # a repeated name on another tier is no ambiguity for the phones


def test_two_alignments_beside_the_input_are_said_and_a_wav_beside_it_checked(tmp_path):
    data = _csv(tmp_path / "b.csv")
    _tg(tmp_path / "b.TextGrid")
    (tmp_path / "b.lab").write_text("0 0.3 m\n0.3 0.6 iy\n")
    (tmp_path / "b.wav").write_text("a text file, not sound\n")
    c = read_corpus(data)
    assert [p.label for p in c.utterances[0].phones] == ["p", "aa"]
    said = " | ".join(c.history)
    assert "b.TextGrid and b.lab are beside it: the phones are read from b.TextGrid" in said
    assert "b.wav beside it was not linked as its audio: not a WAV file" in said and c.utterances[0].audio is None
    import scipy.io.wavfile

    scipy.io.wavfile.write(tmp_path / "b.wav", 16000, np.zeros(1600, np.int16))
    c = read_corpus(data)
    assert c.utterances[0].audio and any("audio b.wav linked" in h for h in c.history)


def _mview(path, srate=100.0, extra=None):
    dt = [("NAME", "O"), ("SRATE", "O"), ("SIGNAL", "O")]
    s = np.zeros((1, 2), dtype=dt)
    s[0, 0] = ("UL", srate, np.random.default_rng(1).normal(size=(40, 6)).astype(np.float32))
    s[0, 1] = ("LL", srate, np.random.default_rng(2).normal(size=(40, 6)).astype(np.float32))
    scipy.io.savemat(path, {path.stem: s, **({"other": s} if extra else {})})
    return path


def test_mview_srate_must_be_one_real_number_and_the_file_one_struct(tmp_path):
    with pytest.raises(ImportFormatError, match=r"entry 1 \(UL\) SRATE is \[\[100. 200.\]\]; expected one rate"):
        read_mview(_mview(tmp_path / "a.mat", srate=np.array([[100.0, 200.0]])), sensors=("UL", "LL"))
    with pytest.raises(ImportFormatError, match="SRATE is .*expected one rate"):
        read_mview(_mview(tmp_path / "c.mat", srate=np.complex128(100 + 5j)), sensors=("UL", "LL"))
    with pytest.raises(ImportFormatError, match="holds 2 MVIEW struct arrays"):
        read_mview(_mview(tmp_path / "two.mat", extra=True), sensors=("UL", "LL"))
    assert read_mview(_mview(tmp_path / "ok.mat"), sensors=("UL", "LL")).rate == 100.0

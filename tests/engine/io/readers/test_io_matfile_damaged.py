"""MAT v5 files whose compressed variable lacks the end of its zlib stream: read when every data byte is there,
and said so per file (what was recovered, what could not be checked); refused, with the bytes recovered, when
data is missing."""
import struct
import zlib

import numpy as np
import pytest

from engine.io import ImportFormatError, read_corpus, read_matrix
from engine.io.readers.matfile import read_mat


def _elements(data):
    """(offset, type, nbytes) of the top-level data elements after the 128-byte header."""
    out, pos = [], 128
    while pos < len(data):
        t, n = struct.unpack("<II", data[pos:pos + 8])
        out.append((pos, t, n))
        pos += 8 + n
    return out


def _cut_zlib_end(path, *, cut, keep_tag=False, element=0):
    """Remove the last ``cut`` bytes of a compressed element's zlib stream (its Adler-32 checksum is the last 4).

    ``keep_tag=False``: the element's tag is shortened to match (a writer that never closed the stream); True:
    the tag keeps its length and the file ends early (cut short). Returns the variable's inflated size.
    """
    data = bytearray(path.read_bytes())
    pos, t, n = _elements(data)[element]
    assert t == 15  # miCOMPRESSED
    stream = bytes(data[pos + 8:pos + 8 + n])
    full = len(zlib.decompress(stream))
    if keep_tag:
        assert element == len(_elements(data)) - 1, "only the last element can end the file"
        del data[pos + 8 + n - cut:]
    else:
        struct.pack_into("<I", data, pos + 4, n - cut)
        del data[pos + 8 + n - cut:pos + 8 + n]
    path.write_bytes(bytes(data))
    return full


@pytest.fixture
def recording(tmp_path):
    """ABCFIA01.mat: a 7-sensor x 6-value articulograph matrix at 250 Hz, written compressed as MATLAB does."""
    import scipy.io

    from engine.talker.multispeaker import generate_recordings

    r = generate_recordings(n_speakers=1, n_utterances=1, duration_s=(0.8, 0.8), seed=2)[0]
    p = tmp_path / "ABCFIA01.mat"
    scipy.io.savemat(p, {"data": r.matrix, "fs": np.array([[250.0]])}, do_compression=True)
    return p, r.matrix


def test_a_stream_without_its_end_is_read_and_said(recording):
    p, M = recording
    full = _cut_zlib_end(p, cut=4)  # the checksum gone, every data byte there
    notes = []
    m = read_mat(p, notes=notes)
    np.testing.assert_array_equal(m["data"], M)
    assert len(notes) == 1
    assert "variable 'data'" in notes[0] and "lacks its end-of-stream marker and Adler-32 checksum" in notes[0]
    assert f"all {full:,} bytes of variable 'data' were recovered and read" in notes[0]
    assert "cannot be verified against the checksum" in notes[0]
    c = read_matrix(p, layout="ema7x6")
    assert c.n_frames == M.shape[0]
    assert any(h.startswith("ABCFIA01.mat: damaged MAT-file:") for h in c.history)


def test_a_file_cut_short_inside_the_stream_end_is_read_and_said(recording):
    p, M = recording
    _cut_zlib_end(p, cut=4, keep_tag=True, element=1)  # 'fs' is written last: the file ends inside its stream
    notes = []
    m = read_mat(p, notes=notes)
    assert float(m["fs"].ravel()[0]) == 250.0
    assert len(notes) == 1 and "the file ends 4 bytes before the end of the compressed element" in notes[0]
    assert "variable 'fs'" in notes[0]


def test_missing_data_bytes_are_refused_with_what_was_recovered(recording):
    p, _ = recording
    full = _cut_zlib_end(p, cut=40)  # deflate data gone too
    with pytest.raises(ImportFormatError) as err:
        read_mat(p)
    msg = str(err.value)
    assert "ABCFIA01.mat" in msg and "its zlib stream lacks its end and variable 'data' cannot be read" in msg
    assert "bytes were recovered" in msg and f"of its {full:,} bytes are missing" in msg


def test_an_intact_file_has_no_note(recording):
    p, M = recording
    notes = []
    np.testing.assert_array_equal(read_mat(p, notes=notes)["data"], M)
    assert notes == []


def test_a_damaged_mview_struct_is_read_and_said(tmp_path):
    """An MVIEW struct array (NAME, SRATE, SIGNAL per sensor), the Haskins layout, compressed and damaged."""
    import scipy.io

    rng = np.random.default_rng(0)
    names = ("UL", "LL", "ML", "JAW", "JAWL")
    s = np.zeros((1, len(names)), dtype=[("NAME", "O"), ("SRATE", "O"), ("SIGNAL", "O")])
    for k, n in enumerate(names):
        s[0, k] = (n, 100.0, np.cumsum(rng.normal(size=(120, 6)), axis=0))
    p = tmp_path / "XYMNE16.mat"
    scipy.io.savemat(p, {"XYMNE16": s}, do_compression=True)
    _cut_zlib_end(p, cut=4)
    c = read_corpus(p)
    assert c.n_frames == 120 and c.point_names == list(names)
    assert [h.split(":", 2)[:2] for h in c.history if "damaged" in h] == [["XYMNE16.mat", " damaged MAT-file"]]


def test_import_says_so_per_file(tmp_path, capsys):
    import scipy.io

    from app.cli import main
    from engine.talker.multispeaker import generate_recordings

    paths = []
    for k, r in enumerate(generate_recordings(n_speakers=1, n_utterances=3, duration_s=(0.8, 0.8), seed=4)):
        p = tmp_path / f"ABCFIA{k + 1:02d}.mat"
        scipy.io.savemat(p, {"data": r.matrix, "fs": np.array([[250.0]])}, do_compression=True)
        paths.append(p)
    _cut_zlib_end(paths[0], cut=4)
    _cut_zlib_end(paths[2], cut=5)
    out = tmp_path / "c.npz"
    assert main(["import", *map(str, paths), "--layout", "ema7x6", "--speaker", "ABC", "-q", "--jobs", "1",
                 "-o", str(out)]) == 0
    err = capsys.readouterr().err
    damaged = [ln for ln in err.splitlines() if "damaged MAT-file" in ln]
    assert [ln.split(": ")[1] for ln in damaged] == ["ABCFIA01.mat", "ABCFIA03.mat"]
    from engine.recordings.corpus import Corpus

    assert len([h for h in Corpus.load(out).history if "damaged MAT-file" in h]) == 2  # info shows them

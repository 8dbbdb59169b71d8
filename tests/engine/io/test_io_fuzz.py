"""Malformed input to every importer: it raises ImportFormatError (CorpusError for the native
.npz file, whose reader belongs to engine.recordings.corpus) or returns a valid corpus -- never another
exception, never a hang."""
import io
import re
import warnings

import c3d
import numpy as np
import pytest
import scipy.io
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from engine.io import (
    ImportFormatError,
    read_alignment,
    read_corpus,
    write_est_track,
    write_obj,
    write_ply,
    write_trajectory_csv,
)
from engine.recordings.corpus import Corpus, CorpusError, Utterance

SETTINGS = settings(max_examples=50, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


# ------------------------------------------------------------------ valid samples to damage
def _lab(tmp):
    return b"0 0.25 sil\n0.25 0.31 m\n0.31 0.52 aa\n0.52 0.6 p\n0.6 0.9 sil\n"


def _textgrid(tmp):
    iv = [(0, 0.2, ""), (0.2, 0.4, "m"), (0.4, 0.7, "aa"), (0.7, 1.0, "")]
    out = ['File type = "ooTextFile"', 'Object class = "TextGrid"', "", "xmin = 0", "xmax = 1", "tiers? <exists>",
           "size = 1", "item []:", "    item [1]:", '        class = "IntervalTier"', '        name = "phones"',
           "        xmin = 0", "        xmax = 1", f"        intervals: size = {len(iv)}"]
    for k, (s, e, lab) in enumerate(iv, 1):
        out += [f"        intervals [{k}]:", f"            xmin = {s}", f"            xmax = {e}",
                f'            text = "{lab}"']
    return ("\n".join(out) + "\n").encode()


def _est_binary(tmp):
    t = np.arange(30) / 500.0
    v = np.random.default_rng(0).normal(size=(30, 20)) * 100
    return write_est_track(tmp / "src.ema", t, v, [f"c{k}" for k in range(20)]).read_bytes()


def _mocha_ascii(tmp):
    rng = np.random.default_rng(1)
    rows = [f"{k / 500:.6f}\t1 \t" + " ".join(f"{x:.6f}" for x in rng.normal(0, 500, 20)) for k in range(30)]
    return ("\n".join(rows) + "\n").encode()


def _mat(tmp):
    dt = [("NAME", "O"), ("SRATE", "O"), ("SIGNAL", "O"), ("SENTENCE", "O"), ("PHONES", "O")]
    s = np.zeros((1, 3), dtype=dt)
    ph = np.zeros((1, 2), dtype=[("LABEL", "O"), ("OFFS", "O")])
    ph[0, 0] = ("M", np.array([[0.0, 0.1]]))
    ph[0, 1] = ("AA1", np.array([[0.1, 0.25]]))
    rng = np.random.default_rng(2)
    s[0, 0] = ("AUDIO", 44100.0, rng.normal(size=(1000, 1)).astype(np.float32), "ma", ph)
    s[0, 1] = ("UL", 100.0, rng.normal(size=(30, 6)).astype(np.float32), "", np.zeros((0, 0)))
    s[0, 2] = ("LL", 100.0, rng.normal(size=(30, 6)).astype(np.float32), "", np.zeros((0, 0)))
    p = tmp / "src.mat"
    scipy.io.savemat(p, {"x": s})
    return p.read_bytes()


def _c3d(tmp):
    w = c3d.Writer(point_rate=60.0)
    w.set_point_labels(["A", "B"])
    for i in range(20):
        p = np.zeros((2, 5), np.float32)
        p[:, :3] = i
        w.add_frames([(p, np.zeros((0, 0)))])
    buf = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        w.write(buf)
    return buf.getvalue()


def _obj(tmp):
    return write_obj(tmp / "src.obj", np.eye(3), [[0, 1, 2]]).read_bytes()


def _ply_ascii(tmp):
    return write_ply(tmp / "src.ply", np.eye(3), [[0, 1, 2]]).read_bytes()


def _ply_binary(tmp):
    return write_ply(tmp / "srcb.ply", np.eye(3), [[0, 1, 2]], binary=True).read_bytes()


def _csv_named(tmp):
    X = np.random.default_rng(3).normal(size=(20, 4))
    return write_trajectory_csv(tmp / "src.csv", X, rate=30, columns=["a_x", "a_y", "b_x", "b_y"]).read_bytes()


def _csv_openface(tmp):
    xy = [f"x_{i}" for i in range(3)] + [f"y_{i}" for i in range(3)]
    head = "frame, face_id, timestamp, success, " + ", ".join(xy)
    rows = [f"{k + 1}, 0, {k / 30:.3f}, 1, " + ", ".join(str(k + i) for i in range(6)) for k in range(20)]
    return (head + "\n" + "\n".join(rows) + "\n").encode()


def _csv_long(tmp):
    rows = ["time,point,x,y,z"] + [f"{f / 25:.3f},p{k},{f},{k},0" for f in range(10) for k in range(2)]
    return ("\n".join(rows) + "\n").encode()


def _npy(tmp):
    buf = io.BytesIO()
    np.save(buf, np.random.default_rng(4).normal(size=(10, 4, 3)).astype(np.float32))
    return buf.getvalue()


def _npz(tmp):
    c = Corpus(frames=np.random.default_rng(5).normal(size=(10, 6)), rate=50, utterances=[Utterance("u", 0, 10)])
    return c.save(tmp / "src.npz").read_bytes()


# name: (sample maker, file name, reader call, exceptions accepted)
CASES = {
    "lab": (_lab, "x.lab", lambda p: read_alignment(p), (ImportFormatError,)),
    "textgrid": (_textgrid, "x.TextGrid", lambda p: read_alignment(p), (ImportFormatError,)),
    "est": (_est_binary, "x.ema", lambda p: read_corpus(p, sensors="all"), (ImportFormatError,)),
    "mocha_ascii": (_mocha_ascii, "x.ema", lambda p: read_corpus(p), (ImportFormatError,)),
    "mview": (_mat, "x.mat", lambda p: read_corpus(p, sensors=("UL", "LL")), (ImportFormatError,)),
    "c3d": (_c3d, "x.c3d", lambda p: read_corpus(p), (ImportFormatError,)),
    "obj": (_obj, "x.obj", lambda p: _mesh_pair(p), (ImportFormatError,)),
    "ply_ascii": (_ply_ascii, "x.ply", lambda p: _mesh_pair(p), (ImportFormatError,)),
    "ply_binary": (_ply_binary, "x.ply", lambda p: _mesh_pair(p), (ImportFormatError,)),
    "csv_named": (_csv_named, "x.csv", lambda p: read_corpus(p), (ImportFormatError,)),
    "csv_openface": (_csv_openface, "x.csv", lambda p: read_corpus(p), (ImportFormatError,)),
    "csv_long": (_csv_long, "x.csv", lambda p: read_corpus(p), (ImportFormatError,)),
    "npy": (_npy, "x.npy", lambda p: read_corpus(p, rate=30), (ImportFormatError,)),
    "npz": (_npz, "x.npz", lambda p: read_corpus(p), (ImportFormatError, CorpusError)),
}


def _mesh_pair(p):
    """A two-frame sequence: the damaged file and an intact copy of the sample."""
    d = p.parent / "seq"
    d.mkdir(exist_ok=True)
    for f in d.iterdir():
        f.unlink()
    (d / f"a{p.suffix}").write_bytes(p.read_bytes())
    src = p.parent / f"src{p.suffix}"
    (d / f"b{p.suffix}").write_bytes(src.read_bytes() if src.exists() else p.read_bytes())
    return read_corpus(d, rate=30)


def _outcome(case, tmp, data):
    make, name, call, accepted = CASES[case]
    path = tmp / name
    path.write_bytes(data)
    try:
        out = call(path)
    except accepted as exc:
        assert str(exc)  # a message, naming something
        if isinstance(exc, ImportFormatError):
            assert exc.path and str(exc).startswith(exc.path)
        return exc
    if isinstance(out, Corpus):
        out.validate()
        assert np.isfinite(out.frames).all()
    else:
        assert all(p.end >= p.start >= 0 for p in out)
    return out


@st.composite
def damaged(draw, base: bytes):
    op = draw(st.sampled_from(["truncate", "overwrite", "insert", "drop_line", "token", "random"]))
    if op == "random" or not base:
        return draw(st.binary(max_size=600))
    if op == "truncate":
        return base[:draw(st.integers(0, max(len(base) - 1, 0)))]
    if op == "overwrite":
        i = draw(st.integers(0, len(base) - 1))
        junk = draw(st.binary(min_size=1, max_size=16))
        return base[:i] + junk + base[i + len(junk):]
    if op == "insert":
        i = draw(st.integers(0, len(base)))
        return base[:i] + draw(st.binary(min_size=1, max_size=16)) + base[i:]
    lines = base.split(b"\n")
    k = draw(st.integers(0, len(lines) - 1))
    if op == "drop_line":
        del lines[k]
    else:
        tok = lines[k].split()
        if tok:
            j = draw(st.integers(0, len(tok) - 1))
            tok[j] = draw(st.sampled_from([b"nan", b"NaN", b"inf", b"x", b"", b"1e999", b"-1", b"0", b'"', b",,"]))
            lines[k] = b" ".join(tok)
    return b"\n".join(lines)


@pytest.mark.parametrize("case", sorted(CASES))
def test_intact_samples_read(tmp_path, case):
    out = _outcome(case, tmp_path, CASES[case][0](tmp_path))
    assert not isinstance(out, Exception), out


@pytest.mark.parametrize("case", sorted(CASES))
def test_damaged_input_never_escapes_as_another_error(tmp_path, case):
    base = CASES[case][0](tmp_path)

    @SETTINGS
    @given(data=damaged(base))
    def run(data):
        _outcome(case, tmp_path, data)

    run()


@pytest.mark.parametrize("case", ["est", "c3d", "ply_binary", "npy", "mview"])
def test_truncated_binary_files_are_errors(tmp_path, case):
    base = CASES[case][0](tmp_path)

    @settings(max_examples=25, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(cut=st.integers(1, len(base) - 1))
    def run(cut):
        if case == "c3d":  # C3D pads its last 512-byte block: cut past the padding into the frames
            cut = min(cut + 511, len(base))
        out = _outcome(case, tmp_path, base[:len(base) - cut])
        assert isinstance(out, Exception), f"{case}: a file cut by {cut} bytes was read"

    run()


@pytest.mark.parametrize("case, text, match", [
    ("csv_named", b"time,a_x,a_y\n0,1,2\n0.1,1\n", "line 3: 2 fields"),
    ("mocha_ascii", b"0 1 " + b"1 " * 19 + b"\n", "line 1: 21 columns"),
    ("lab", b"0 0.1 a\n0.1 b\n", "line 2"),
    ("textgrid", b'File type = "ooTextFile"\nObject class = "TextGrid"\n\nxmin = 0\nxmax = nan\n', "holds no tiers"),
    ("csv_long", b"frame,point,x,y\n0.00,a,NaN,NaN\n0.01,a,nan,\n", "missing in every frame"),
    ("npy", b"\x93NUMPY\x01\x00", "not a readable .npy"),
])
def test_specific_malformations_are_named(tmp_path, case, text, match):
    if case == "csv_long":
        out = _outcome(case, tmp_path, text.replace(b"frame,", b"time,"))
    else:
        out = _outcome(case, tmp_path, text)
    assert isinstance(out, ImportFormatError) and re.search(match, str(out)), out

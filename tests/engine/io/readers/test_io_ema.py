"""MOCHA-TIMIT EMA: EST Track binary/ASCII written and read back; the real fsew0_001 sample."""
from pathlib import Path

import numpy as np
import pytest

from engine.io import ImportFormatError, read_corpus, read_ema, read_est_track, write_est_track
from engine.io.readers.ema import MOCHA_CHANNELS


def _repo_root():
    p = Path(__file__).resolve()
    while not (p / "pyproject.toml").exists():
        p = p.parent
    return p


MOCHA = _repo_root().parent / "shared" / "data" / "mocha-fsew0"
needs_mocha = pytest.mark.skipif(not (MOCHA / "fsew0_001.ema").exists(),
                                 reason=f"MOCHA sample not found at {MOCHA} (../shared/data beside the project)")


def _track(n=120, rate=500.0, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate
    vals = np.cumsum(rng.normal(0, 5, (n, 20)), axis=0) + 1000
    names = [c.lower() for c in MOCHA_CHANNELS]
    return t, vals, names


@pytest.mark.parametrize("order", ["01", "10"])
def test_est_binary_round_trip(tmp_path, order):
    t, vals, names = _track()
    p = write_est_track(tmp_path / "a.ema", t, vals, names, byte_order=order)
    raw = p.read_bytes()
    assert raw.startswith(b"EST_File Track\n") and b"EST_Header_End\n" in raw
    body = raw[raw.index(b"EST_Header_End\n") + len(b"EST_Header_End\n"):]
    assert len(body) == 120 * (2 + 20) * 4  # time, break, 20 channels, float32 each
    first = np.frombuffer(body[:8], dtype=("<" if order == "01" else ">") + "f4")
    assert first[0] == 0.0 and first[1] == 1.0
    tt, vv, valid, nn = read_est_track(p)
    assert nn == names and valid.all()
    np.testing.assert_allclose(tt, t, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(vv, vals.astype(np.float32), rtol=1e-6)
    c = read_ema(p, alignment=False)
    assert c.rate == 500.0 and c.dims == 2 and c.point_names == ["UL", "LL", "LI"]
    ul = names.index("ul_x"), names.index("ul_y")
    np.testing.assert_allclose(c.frames[:, :2], vals[:, ul].astype(np.float32) * 0.01, rtol=1e-5)


def test_est_ascii_and_breaks_are_interpolated(tmp_path):
    t, vals, names = _track(n=50)
    valid = np.ones(50, bool)
    valid[10:13] = False
    vals[10:13] = 9e9  # garbage under the break flag
    p = write_est_track(tmp_path / "b.ema", t, vals, names, valid=valid, binary=False)
    assert b"DataType ascii" in p.read_bytes()
    c = read_ema(p, sensors="all", alignment=False)
    assert c.n_points == 10 and np.abs(c.frames).max() < 1e3
    j = names.index("ul_x")
    k = c.point_names.index("UL") * 2
    expect = np.interp(np.arange(10, 13), [9, 13], vals[[9, 13], j] * 0.01)
    np.testing.assert_allclose(c.frames[10:13, k], expect, rtol=1e-4)
    with pytest.raises(ImportFormatError, match="UL_x is missing.*break flag 0.*--no-fill") as e:
        read_ema(p, fill_gaps=False, alignment=False)
    assert e.value.frame == 10


def test_est_named_channels_pair_into_sensors(tmp_path):
    t = np.arange(30) / 200.0
    vals = np.column_stack([np.full(30, 100.0), np.full(30, 200.0), np.linspace(0, 1, 30), np.zeros(30)])
    p = write_est_track(tmp_path / "n.ema", t, vals, ["UL x", "UL y", "jaw_x", "jaw_y"])
    c = read_ema(p, sensors=("jaw", "ul"), scale=1.0, alignment=False)
    assert c.rate == 200.0 and c.point_names == ["JAW", "UL"]
    np.testing.assert_allclose(c.frames[0], [0, 0, 100, 200])


@pytest.mark.parametrize("mutate, match, where", [
    (lambda b: b[:-10], "(?i)truncated", "frame"),
    (lambda b: b + b"\0\0\0\0", "bytes follow", None),
    (lambda b: b.replace(b"NumFrames 40", b"NumFrames forty"), "NumFrames is 'forty'; expected an integer", "line"),
    (lambda b: b.replace(b"ByteOrder 01", b"ByteOrder XX"), "ByteOrder is 'XX'", "line"),
    (lambda b: b.replace(b"EST_Header_End", b"EST_Header_Fin"), "no 'EST_Header_End'", None),
    (lambda b: b.replace(b"EST_File Track", b"EST_File Wave "), "expected 'EST_File Track'", "line"),
    (lambda b: b.replace(b"NumChannels 20", b"NumChannels 0"), "NumChannels is 0; expected at least 1", "line"),
])
def test_est_errors_are_located(tmp_path, mutate, match, where):
    t, vals, names = _track(n=40)
    p = write_est_track(tmp_path / "e.ema", t, vals, names)
    p.write_bytes(mutate(p.read_bytes()))
    with pytest.raises(ImportFormatError, match=match) as e:
        read_ema(p, alignment=False)
    assert str(e.value).startswith(str(p))
    if where == "frame":
        assert e.value.frame == 39
    elif where == "line":
        assert e.value.line is not None


def test_mocha_ascii_wrong_columns_names_line(tmp_path):
    p = tmp_path / "x.ema"
    p.write_text("0.000 1 " + " ".join(["1.0"] * 20) + "\n0.002 1 " + " ".join(["1.0"] * 19) + "\n")
    with pytest.raises(ImportFormatError, match=r"x\.ema, line 2: 21 columns; expected 22"):
        read_ema(p)
    p.write_text("0.000 1 " + " ".join(["1.0"] * 20) + "\n0.010 1 " + " ".join(["1.0"] * 20) +
                 "\n0.012 1 " + " ".join(["1.0"] * 20) + "\n0.014 1 " + " ".join(["1.0"] * 20) + "\n")
    with pytest.raises(ImportFormatError, match="uniformly spaced") as e:
        read_ema(p)
    assert e.value.frame == 1


@needs_mocha
def test_real_mocha_sample_loads_at_500_hz():
    c = read_ema(MOCHA / "fsew0_001.ema")
    raw = np.loadtxt(MOCHA / "fsew0_001.ema")
    assert c.rate == 500.0 and c.dims == 2 and c.n_frames == raw.shape[0] == 966
    assert c.point_names == ["UL", "LL", "LI"]
    # column mapping (MOCHAread.m): UL x,y = cols 4, 9; LL = 5, 10; LI = 3, 8; 1/100 mm -> mm
    np.testing.assert_allclose(c.frames, raw[:, [4, 9, 5, 10, 3, 8]] / 100, rtol=1e-5, atol=1e-5)
    # anatomy: the upper lip sits above the lower lip in every frame, the jaw coil well below the upper lip
    P = c.frames.reshape(-1, 3, 2)
    assert (P[:, 0, 1] > P[:, 1, 1]).all() and (P[:, 0, 1] - P[:, 2, 1]).min() > 10
    # every channel: the upper-incisor reference hardly moves; the tongue coils lie front to back TT, TB, TD
    a = read_ema(MOCHA / "fsew0_001.ema", sensors="all").frames.reshape(-1, 10, 2)
    names = list(read_ema(MOCHA / "fsew0_001.ema", sensors="all").point_names)
    std = a.std(axis=0).max(axis=1)
    assert std[names.index("UI")] < 0.3 < 2 < std[names.index("TT")]
    x = a.mean(axis=0)[:, 0]
    assert x[names.index("UL")] < x[names.index("TT")] < x[names.index("TB")] < x[names.index("TD")]
    assert c.utterances[0].audio.endswith("fsew0_001.wav")


@needs_mocha
def test_real_mocha_phones_are_clipped_and_line_up_with_frames():
    c = read_ema(MOCHA / "fsew0_001.ema")
    lab = [ln.split() for ln in (MOCHA / "fsew0_001.lab").read_text().split("\n") if ln.strip()]
    u = c.utterances[0]
    dur = c.n_frames / c.rate
    assert float(lab[-1][1]) > dur  # the .lab runs past the data (2.2 s vs 1.932 s) ...
    assert u.phones[-1].end == pytest.approx(dur) and u.phones[-1].label == lab[-1][2]  # ... and is cut at its end
    assert any("runs to 2.200 s but the data last 1.932 s" in h for h in c.history)  # ... which the user is told
    assert len(u.phones) == len(lab) and [p.label for p in u.phones] == [r[2] for r in lab]
    raw_t = np.loadtxt(MOCHA / "fsew0_001.ema", usecols=0)
    for p, r in zip(u.phones[:-1], lab[:-1]):
        f = c.time_to_frame(u, p.start)
        assert raw_t[f] == pytest.approx(float(r[0]), abs=1e-6)  # the file's own time column at that frame
    mids, labels, *_ = c.phone_table()
    assert mids.max() < c.n_frames and list(labels) == [p.label for p in u.phones]


@needs_mocha
def test_real_mocha_through_read_corpus_with_explicit_alignment(tmp_path):
    lab = tmp_path / "other.lab"
    lab.write_text("0.5 0.7 x\n0.7 0.9 y\n")
    c = read_corpus(MOCHA / "fsew0_001.ema", alignment=lab, sensors="all")
    assert [p.label for p in c.utterances[0].phones] == ["x", "y"] and c.n_points == 10
    with pytest.raises(ImportFormatError, match="500 Hz but a rate of 60 Hz"):
        read_corpus(MOCHA / "fsew0_001.ema", rate=60)

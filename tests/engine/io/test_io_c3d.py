"""C3D marker files, written with c3d.Writer and read back."""
import warnings

import c3d
import numpy as np
import pytest

from engine.io import ImportFormatError, read_c3d, read_corpus


def _write(path, P, *, rate=120.0, labels=None, invalid=(), units="mm  "):
    """P: (n, V, 3) marker positions; invalid: (frame, marker) pairs flagged with residual -1."""
    n, V, _ = P.shape
    w = c3d.Writer(point_rate=rate, point_units=units)
    w.set_point_labels(labels or [f"M{k}" for k in range(V)])
    for i in range(n):
        p = np.zeros((V, 5), np.float32)
        p[:, :3] = P[i]
        for f, m in invalid:
            if f == i:
                p[m, 3] = -1
        w.add_frames([(p, np.zeros((0, 0)))])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the library warns that there is no analog data
        with open(path, "wb") as fh:
            w.write(fh)
    return path


def _markers(n=40, V=4, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n)[:, None, None] / 120.0
    return (rng.normal(0, 20, (1, V, 3)) + 3 * np.sin(2 * np.pi * 4 * t + rng.uniform(0, 6, (1, V, 3)))).astype(
        np.float32)


def test_round_trip(tmp_path):
    P = _markers()
    p = _write(tmp_path / "a.c3d", P, labels=["ULIP", "LLIP", "LCORNER", "RCORNER"])
    c = read_c3d(p)
    assert c.rate == 120.0 and c.dims == 3 and c.n_frames == 40
    assert c.point_names == ["ULIP", "LLIP", "LCORNER", "RCORNER"] and c.utterances[0].id == "a"
    np.testing.assert_allclose(c.frames.reshape(40, 4, 3), P, atol=1e-5)
    assert read_corpus(p).n_frames == 40


def test_marker_selection_units_and_gaps(tmp_path):
    P = _markers()
    p = _write(tmp_path / "b.c3d", P, labels=["A", "B", "C", "D"], invalid=[(10, 1), (11, 1)], units="cm  ")
    c = read_c3d(p, markers=["c", 1])
    assert c.point_names == ["C", "B"]
    F = c.frames.reshape(40, 2, 3)
    np.testing.assert_allclose(F[:, 0], P[:, 2] * 10, atol=1e-4)  # cm -> mm
    expect = P[9, 1] + (P[12, 1] - P[9, 1]) * np.array([[1 / 3], [2 / 3]])
    np.testing.assert_allclose(F[10:12, 1], expect * 10, atol=1e-3)  # dropout interpolated
    with pytest.raises(ImportFormatError, match="B_x is missing") as e:
        read_c3d(p, fill_gaps=False)
    assert e.value.frame == 10
    with pytest.raises(ImportFormatError, match="has no marker 'nose'"):
        read_c3d(p, markers=["nose"])
    with pytest.raises(ImportFormatError, match="120 Hz but a rate of 60 Hz"):
        read_c3d(p, rate=60)


def test_truncated_and_foreign_files(tmp_path):
    p = _write(tmp_path / "c.c3d", _markers(n=200, V=10))
    data = p.read_bytes()
    t = tmp_path / "t.c3d"
    t.write_bytes(data[: len(data) - 5000])
    with pytest.raises(ImportFormatError, match=r"t\.c3d, frame \d+: the data holds \d+ whole frames.*Truncated") as e:
        read_c3d(t)
    assert 0 < e.value.frame < 200
    f = tmp_path / "f.c3d"
    f.write_bytes(b"hello, not c3d" * 100)
    with pytest.raises(ImportFormatError, match="second byte is 0x50"):
        read_c3d(f)

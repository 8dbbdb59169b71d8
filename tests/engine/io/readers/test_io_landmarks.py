"""CSV landmark tracks: OpenFace, named wide (Lipspace's own export), long format."""
import re

import numpy as np
import pytest

from engine.io import ImportFormatError, read_corpus, read_csv_landmarks, write_trajectory_csv
from engine.io.readers.landmarks import IBUG68_LIPS


def _openface(path, n=90, fps=30.0, three_d=True, fail=(), faces=1, seed=0):
    rng = np.random.default_rng(seed)
    base = rng.normal(0, 50, (68, 3))
    head = ["frame", " face_id", " timestamp", " confidence", " success"]
    head += [f" x_{i}" for i in range(68)] + [f" y_{i}" for i in range(68)]
    if three_d:
        head += [f" X_{i}" for i in range(68)] + [f" Y_{i}" for i in range(68)] + [f" Z_{i}" for i in range(68)]
    head += [" AU01_r"]
    rows, truth = [], []
    for k in range(n):
        P = base + 5 * np.sin(2 * np.pi * 2 * k / fps + np.arange(68)[:, None] / 10)
        truth.append(P)
        for f in range(faces):
            ok = 0 if k in fail else 1
            r = [k + 1, f, round(k / fps, 3), 0.98, ok]  # OpenFace rounds timestamps to ms
            r += list(P[:, 0] * 3 + 300) + list(P[:, 1] * 3 + 200)
            if three_d:
                r += list(P[:, 0]) + list(P[:, 1]) + list(P[:, 2] + 500)
            rows.append(r + [0.1])
    path.write_text(", ".join(head) + "\n" + "\n".join(", ".join(f"{v:.3f}" if isinstance(v, float) else str(v)
                                                                   for v in r) for r in rows) + "\n")
    return np.array(truth)


def test_openface_3d_and_2d(tmp_path):
    p = tmp_path / "of.csv"
    T = _openface(p)
    c = read_csv_landmarks(p)
    assert c.rate == 30.0 and c.dims == 3 and c.n_points == 68 and c.point_names[0] == "L0"
    F = c.frames.reshape(90, 68, 3)
    np.testing.assert_allclose(F[..., 0], T[..., 0], atol=1e-3)
    np.testing.assert_allclose(F[..., 2], T[..., 2] + 500, atol=1e-3)
    c2 = read_corpus(p, space="2d", points="lips")
    assert c2.dims == 2 and c2.point_names == [f"L{i}" for i in IBUG68_LIPS]
    np.testing.assert_allclose(c2.frames.reshape(90, 20, 2)[..., 1], T[:, 48:, 1] * 3 + 200, atol=2e-3)


def test_openface_failed_frames_and_several_faces(tmp_path):
    p = tmp_path / "of.csv"
    T = _openface(p, three_d=False, fail=(20, 21), faces=2)
    c = read_csv_landmarks(p, points=[48, 54])
    assert c.n_frames == 90 and c.dims == 2
    x48 = c.frames[:, 0]
    np.testing.assert_allclose(x48[[19, 22]], T[[19, 22], 48, 0] * 3 + 300, atol=2e-3)
    expect = np.interp([20, 21], [19, 22], x48[[19, 22]])
    np.testing.assert_allclose(x48[20:22], expect, atol=1e-3)  # unsuccessful rows are gaps, interpolated
    with pytest.raises(ImportFormatError, match="x_48 is missing") as e:
        read_csv_landmarks(p, points=[48], fill_gaps=False)
    assert e.value.frame == 20


def test_named_wide_round_trip_with_own_export(tmp_path):
    rng = np.random.default_rng(3)
    X = rng.normal(size=(50, 6)).astype(np.float32)
    p = write_trajectory_csv(tmp_path / "t.csv", X, rate=60, columns=["UL_x", "UL_y", "UL_z", "LL_x", "LL_y", "LL_z"])
    c = read_corpus(p)
    assert c.rate == 60 and c.dims == 3 and c.point_names == ["UL", "LL"]
    np.testing.assert_allclose(c.frames, X, rtol=1e-6, atol=1e-6)
    q = write_trajectory_csv(tmp_path / "u.csv", X[:, :4], rate=100, columns=["a_x", "a_y", "b_x", "b_y"])
    assert read_corpus(q).dims == 2


def test_long_format(tmp_path):
    rows = ["frame,point,x,y,z"]
    for f in range(10):
        for nm in ("ul", "ll"):
            rows.append(f"{f},{nm},{f},{1 if nm == 'ul' else -1},0")
    p = tmp_path / "long.csv"
    p.write_text("\n".join(rows) + "\n")
    with pytest.raises(ImportFormatError, match="no time column; give the frame rate"):
        read_csv_landmarks(p)
    c = read_csv_landmarks(p, rate=50)
    assert c.point_names == ["ul", "ll"] and c.n_frames == 10 and c.dims == 3
    np.testing.assert_array_equal(c.frames[3], [3, 1, 0, 3, -1, 0])
    p.write_text("\n".join(rows[:-1]) + "\n9,ul,9,1,0\n")
    with pytest.raises(ImportFormatError, match="'ul' appears twice in frame 9") as e:
        read_csv_landmarks(p, rate=50)
    assert e.value.line == 21
    t = tmp_path / "timed.csv"
    t.write_text("time;marker;x;y\n" + "\n".join(f"{f / 25:.4f};m{k};{f};{k}" for f in range(20) for k in range(3)))
    c = read_corpus(t)
    assert c.rate == 25.0 and c.dims == 2 and c.n_points == 3


@pytest.mark.parametrize("text, line, match", [
    ("time,a_x,a_y\n0,1,2\n0.01,1\n", 3, "2 fields; the header has 3"),
    ("time,a_x,a_y\n0,1,2\n0.01,1,two\n", 3, "column 'a_y' is 'two'; expected a number"),
    ("time,foo,bar\n0,1,2\n0.01,1,2\n", 1, "no landmark columns"),
])
def test_csv_errors_name_the_line(tmp_path, text, line, match):
    p = tmp_path / "e.csv"
    p.write_text(text)
    with pytest.raises(ImportFormatError, match=match) as e:
        read_csv_landmarks(p)
    assert e.value.line == line


def test_csv_timing_errors(tmp_path):
    p = tmp_path / "e.csv"
    p.write_text("a_x,a_y\n1,2\n1,2\n")
    with pytest.raises(ImportFormatError, match="no time column"):
        read_csv_landmarks(p)
    assert read_csv_landmarks(p, rate=10).rate == 10
    p.write_text("time,a_x,a_y\n0,1,2\n0.1,1,2\n0.2,1,2\n0.5,1,2\n0.6,1,2\n")
    with pytest.raises(ImportFormatError, match="dropped or repeated frames") as e:
        read_csv_landmarks(p)
    assert e.value.frame == 3
    p.write_text("a_x,a_y,b_x,b_y,b_z\n1,2,3,4,5\n1,2,3,4,5\n")
    with pytest.raises(ImportFormatError, match="point 'a' has no z column"):
        read_csv_landmarks(p, rate=10)


def test_time_column_and_a_different_rate_is_refused(tmp_path):
    """A CSV's own times decide its rate: a --rate that disagrees is an error, not silently used."""
    p = tmp_path / "t.csv"
    p.write_text("time,a_x,a_y\n" + "".join(f"{k / 100:.2f},{k},{-k}\n" for k in range(20)))
    with pytest.raises(ImportFormatError,
                       match=r"time column 'time' gives 100 Hz but a rate of 60 Hz was given \(--rate\)"):
        read_csv_landmarks(p, rate=60)
    assert read_csv_landmarks(p, rate=100).rate == 100 == read_csv_landmarks(p).rate
    q = tmp_path / "long.csv"
    q.write_text("time,point,x,y\n" + "".join(f"{k / 50:.2f},m,{k},0\n" for k in range(10)))
    with pytest.raises(ImportFormatError, match=r"gives 50 Hz but a rate of 25 Hz"):
        read_csv_landmarks(q, rate=25)


def test_long_table_frame_gaps_are_filled_and_named(tmp_path):
    """Missing frame numbers are dropouts (interpolated, the history naming them), never closed up."""
    p = tmp_path / "gaps.csv"
    p.write_text("frame,point,x,y\n" + "".join(f"{f},m,{2 * f},1\n" for f in (0, 1, 2, 5, 6, 7)))
    c = read_csv_landmarks(p, rate=10)
    assert [h for h in c.history if "4 without a row in the table" in h and "2 of 8 frames (frames 3, 4)" in h]
    assert c.n_frames == 8  # not 6: the track keeps its timing
    np.testing.assert_allclose(c.frames[:, 0], 2 * np.arange(8))  # the gap interpolated linearly
    with pytest.raises(ImportFormatError, match="missing") as e:
        read_csv_landmarks(p, rate=10, fill_gaps=False)
    assert e.value.frame == 3
    p.write_text("frame,point,x,y\n0,m,0,0\n1,m,1,1\n1000000000,m,2,2\n")  # a typo: no billion-row array
    with pytest.raises(ImportFormatError, match=r"999999998 of those 1000000001 frames have no rows \(2, 3, 4"):
        read_csv_landmarks(p, rate=10)
    p.write_text("frame,point,x,y\n0,m,0,0\n0.5,m,1,1\n1,m,2,2\n")
    with pytest.raises(ImportFormatError, match="frame number 0.5 .* not a whole number") as e:
        read_csv_landmarks(p, rate=10)
    assert e.value.line == 3


def test_alignment_longer_than_the_data(tmp_path):
    """Cut and reported naming both durations; refused when it is many times as long (wrong file or rate)."""
    p = tmp_path / "a.csv"
    p.write_text("time,a_x,a_y\n" + "".join(f"{k / 100:.2f},{k},0\n" for k in range(100)))  # 1.00 s
    lab = tmp_path / "a.lab"
    lab.write_text("0 0.5 p\n0.5 25 aa\n")
    with pytest.raises(ImportFormatError, match=r"runs to 25\.000 s but the data last 1\.000 s .*25\.0 times"):
        read_corpus(p, alignment=lab)
    lab.write_text("0 0.5 p\n0.5 1.3 aa\n1.3 1.4 m\n")
    c = read_corpus(p, alignment=lab)
    assert [h for h in c.history if re.search(r"runs to 1\.400 s but the data last 1\.000 s.*1 phone dropped", h)]
    assert [ph.label for ph in c.utterances[0].phones] == ["p", "aa"] and c.utterances[0].phones[-1].end == 1.0
    lab.write_text("0 0.5 p\n0.5 1.0 aa\n1.0 3.5 sil\n")  # a trailing pause past the data: cut, never refused,
    c = read_corpus(p, alignment=lab)  # and said (where the utterance ends is not what the alignment says)
    assert [h for h in c.history if re.search(r"runs to 3\.500 s but the data last 1\.000 s.*'sil'", h)]
    assert [ph.label for ph in c.utterances[0].phones] == ["p", "aa"]

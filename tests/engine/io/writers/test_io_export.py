"""Exporters: trajectory CSV / NPY, mesh sequences, tables; every write is atomic."""
import csv

import numpy as np
import pytest

import engine.io.writers.export as export
from engine.io import (
    corpus_columns,
    read_mesh_sequence,
    write_mesh_sequence,
    write_table_csv,
    write_trajectory_csv,
    write_trajectory_npy,
)
from engine.recordings.corpus import Corpus, Utterance


def _rows(p):
    return list(csv.reader(p.read_text().splitlines()))


def test_trajectory_csv_has_a_time_column_and_named_columns(tmp_path):
    Y = np.arange(12, dtype=float).reshape(4, 3) / 7
    p = write_trajectory_csv(tmp_path / "y.csv", Y, rate=60, columns=["y1", "y2", "y3"])
    rows = _rows(p)
    assert rows[0] == ["time", "y1", "y2", "y3"] and len(rows) == 5
    got = np.array(rows[1:], dtype=float)
    np.testing.assert_allclose(got[:, 0], np.arange(4) / 60, rtol=1e-6)
    np.testing.assert_allclose(got[:, 1:], Y, rtol=1e-6)
    q = write_trajectory_csv(tmp_path / "z.csv", Y[:, 0], times=[0, 0.5, 1, 2])
    assert _rows(q)[0] == ["time", "c0"]
    with pytest.raises(ValueError, match="give rate"):
        write_trajectory_csv(tmp_path / "w.csv", Y)
    with pytest.raises(ValueError, match="2 column names for 3 columns"):
        write_trajectory_csv(tmp_path / "w.csv", Y, rate=1, columns=["a", "b"])
    assert not (tmp_path / "w.csv").exists()


def test_trajectory_npy_and_corpus_columns(tmp_path):
    Y = np.random.default_rng(0).normal(size=(5, 2))
    p = write_trajectory_npy(tmp_path / "y.npy", Y)
    got = np.load(p)
    assert got.dtype == np.float32 and np.allclose(got, Y, atol=1e-6)
    c = Corpus(frames=np.zeros((3, 4)), rate=10, utterances=[Utterance("a", 0, 3)], dims=2, point_names=["UL", "LL"])
    assert corpus_columns(c) == ["UL_x", "UL_y", "LL_x", "LL_y"]


def test_mesh_sequence_of_2d_points_without_faces(tmp_path):
    F = np.arange(12, dtype=np.float32).reshape(3, 4)  # 3 frames, two 2-D points
    files = write_mesh_sequence(tmp_path / "pts", F, dims=2, format="ply")
    assert [f.name for f in files] == ["frame_00000.ply", "frame_00001.ply", "frame_00002.ply"]
    c = read_mesh_sequence(tmp_path / "pts", rate=30)
    assert c.faces is None
    np.testing.assert_array_equal(c.frames.reshape(3, 2, 3)[..., :2], F.reshape(3, 2, 2))
    assert (c.frames.reshape(3, 2, 3)[..., 2] == 0).all()


def test_table_csv_from_rows_and_columns(tmp_path):
    rows = [{"phone": "m", "count": np.int64(120), "opening": 0.25, "sep": float("inf")},
            {"phone": "p", "count": 80, "opening": float("nan"), "extra": "x"}]
    p = write_table_csv(tmp_path / "t.csv", rows)
    got = _rows(p)
    assert got == [["phone", "count", "opening", "sep", "extra"], ["m", "120", "0.25", "inf", ""],
                   ["p", "80", "", "", "x"]]
    q = write_table_csv(tmp_path / "c.csv", {"phone": ["a", "b"], "mean": [np.array([1.0, 2.0]), [3, 4]]})
    assert _rows(q) == [["phone", "mean"], ["a", "1 2"], ["b", "3 4"]]
    with pytest.raises(ValueError, match="different lengths"):
        write_table_csv(tmp_path / "bad.csv", {"a": [1], "b": [1, 2]})


def _boom(*a, **k):
    raise OSError("disk full (simulated)")


@pytest.mark.parametrize("write", [
    lambda p: write_trajectory_csv(p, np.ones((100, 3)), rate=60),
    lambda p: write_table_csv(p, [{"a": object.__new__(type("Bad", (), {"__str__": _boom}))}]),
    lambda p: write_trajectory_npy(p, np.ones((10, 2))),
])
def test_a_failing_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch, write):
    p = tmp_path / "out.dat"
    p.write_text("old contents\n")
    monkeypatch.setattr(np, "savetxt", _boom)
    monkeypatch.setattr(np, "save", _boom)
    with pytest.raises(OSError, match="simulated"):
        write(p)
    assert p.read_text() == "old contents\n"
    assert [f.name for f in tmp_path.iterdir()] == ["out.dat"]


def test_a_failing_mesh_export_keeps_finished_frames_whole(tmp_path, monkeypatch):
    F = np.zeros((4, 9), np.float32)
    calls = {"n": 0}
    real = export.write_obj

    def flaky(path, *a, **k):
        calls["n"] += 1
        if calls["n"] == 3:
            raise OSError("disk full (simulated)")
        return real(path, *a, **k)

    monkeypatch.setattr(export, "write_obj", flaky)
    with pytest.raises(OSError):
        write_mesh_sequence(tmp_path / "m", F)
    names = sorted(f.name for f in (tmp_path / "m").iterdir())
    assert names == ["frame_00000.obj", "frame_00001.obj"]  # no half file, no temporary

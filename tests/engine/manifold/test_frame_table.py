"""The per-frame table and the Praat tiers of a manifold (engine side), and the TextGrid writer."""
from __future__ import annotations

import re

import numpy as np
import pytest

from engine.io.writers.praat import IntervalTier, PointTier, textgrid_names, textgrid_text, write_textgrid
from engine.manifold.frame_table import CLASS_LABELS, class_intervals, frame_table, utterance_tiers


@pytest.fixture(scope="module")
def table(small_manifold):
    return frame_table(small_manifold)


def test_sv_coordinates_are_the_opening_and_its_velocity(small_manifold, table):
    from engine.recordings.kinematics import lip_aperture

    t = small_manifold.tangent_
    sv = t.sv_coordinates()
    np.testing.assert_allclose(sv[:, 0], lip_aperture(small_manifold.corpus_), rtol=1e-5)
    np.testing.assert_allclose(sv[:, 1], t.velocity_, rtol=1e-6)
    assert np.all(sv[t.opening_, 1] > 0)  # the opening class is the sign of V
    # S is the lip aperture itself: written once, as lip_aperture, and said so
    assert "s" not in table.columns and any("lip_aperture itself" in n for n in table.notes)
    np.testing.assert_allclose(table.columns["lip_aperture"], sv[:, 0], rtol=1e-5)
    np.testing.assert_allclose(table.columns["v"], sv[:, 1])
    o, S, V = t.sv_basis()  # the drawn frame in Y1-3
    assert abs(S @ V) < 1e-12 and np.isclose(np.linalg.norm(S), 1) and np.isclose(np.linalg.norm(V), 1)


def test_one_row_per_frame_with_snake_case_columns_and_units(small_manifold, table):
    c, m = small_manifold.corpus_, small_manifold
    assert table.n_rows == c.n_frames
    names = list(table.columns)
    assert names[:10] == ["utterance", "speaker", "time_s", "frame", "phone", "landmark", "lip_aperture", "class",
                          "state", "v"]
    assert names[10:] == [f"fx_{j}" for j in range(1, m.Fx_.shape[1] + 1)] + ["fy_1", "fy_2", "fy_3"]
    assert all(re.fullmatch(r"[a-z][a-z0-9_]*", n) for n in names)
    assert set(table.units) == set(names) == set(table.descriptions)
    assert table.units["time_s"] == "s" and table.units["lip_aperture"] == "mm"
    assert table.units["v"] == "mm per s"
    assert set(table.columns["speaker"]) == {"unknown"}  # the talker names no speaker: a word, not NA
    # the talker names its lips (the inner-contour mid-points): the aperture is theirs
    from engine.recordings.kinematics import lip_aperture

    np.testing.assert_allclose(table.columns["lip_aperture"], lip_aperture(c))
    for u in c.utterances:
        sl = slice(u.start, u.stop)
        assert set(table.columns["utterance"][sl]) == {u.id}
        np.testing.assert_allclose(table.columns["time_s"][sl], np.arange(u.n_frames) / c.rate)
        cls = table.columns["class"][sl]
        assert all(x in CLASS_LABELS for x in cls)  # every frame of a longer utterance has a (central) step
        for p in u.phones:  # the frame nearest a phone's middle carries its label
            f = int(np.floor(p.mid * c.rate))
            if p.start <= f / c.rate < p.end:
                assert table.columns["phone"][u.start + f] == p.label
    np.testing.assert_array_equal(table.columns["state"], m.states_.labels_)
    np.testing.assert_array_equal(table.columns["fy_2"], m.Fy_[:, 1])


def test_the_class_s_and_v_columns_come_from_tangent_columns_alone(small_manifold, monkeypatch):
    """The lead repoints the tangent frames in one place: engine.manifold.frame_table.tangent_columns."""
    import engine.manifold.frame_table as ft

    N = small_manifold.corpus_.n_frames
    fake = {"class": np.array(["x"] * N, dtype=object), "s": np.full(N, 7.0), "v": np.full(N, -3.0)}
    monkeypatch.setattr(ft, "tangent_columns", lambda m: fake)
    t = ft.frame_table(small_manifold, n_fx=0)
    assert set(t.columns["class"]) == {"x"} and set(t.columns["s"]) == {7.0} and set(t.columns["v"]) == {-3.0}
    assert set(ft.utterance_tiers(small_manifold, t, small_manifold.corpus_.utterances[0].id)[2][1].intervals[0][2]) \
        == {"x"}


def test_landmarks_are_the_kinematic_landmarks_of_the_opening_measure(small_manifold, table):
    from engine.recordings.kinematics import kinematic_landmarks, lip_aperture

    f, lab = kinematic_landmarks(small_manifold.corpus_, aperture=lip_aperture(small_manifold.corpus_))
    lm = table.columns["landmark"]
    assert np.flatnonzero(lm != None).tolist() == f.tolist()  # noqa: E711 (object array)
    assert lm[f].tolist() == lab.tolist()


def test_n_fx_limits_the_shape_columns(small_manifold):
    t = frame_table(small_manifold, n_fx=2)
    assert [n for n in t.columns if n.startswith("fx_")] == ["fx_1", "fx_2"]
    with pytest.raises(ValueError, match="shape components"):
        frame_table(small_manifold, n_fx=999)


def test_class_intervals_merge_runs_and_leave_the_last_frame_out():
    labs = ["a", "a", "b", "b", "b", "a", None]
    assert class_intervals(labs, 10.0) == [(0.0, 0.2, "a"), (0.2, 0.5, "b"), (0.5, 0.6, "a")]
    assert class_intervals([None], 60.0) == []


def test_utterance_tiers_hold_phones_classes_and_landmarks(small_manifold, table, tmp_path):
    from engine.io import read_textgrid
    from engine.io.readers.alignment import _parse_textgrid, textgrid_tiers

    c = small_manifold.corpus_
    u = c.utterances[1]
    xmin, xmax, tiers = utterance_tiers(small_manifold, table, u.id)
    p = write_textgrid(tmp_path / "u.TextGrid", xmin, xmax, tiers)
    assert textgrid_tiers(p) == {"phones": "IntervalTier", "class": "IntervalTier", "landmarks": "PointTier"}
    assert [(q.start, q.end, q.label) for q in read_textgrid(p)] == [(q.start, q.end, q.label) for q in u.phones]
    g = _parse_textgrid(p)
    runs = class_intervals(table.columns["class"][u.start:u.stop], c.rate)
    got = [(iv.xmin, iv.xmax, iv.text) for iv in g["class"] if iv.text]
    assert len(got) == len(runs) and all(a[2] == b[2] and abs(a[0] - b[0]) < 1e-9 for a, b in zip(got, runs))
    lm = [x for x in table.columns["landmark"][u.start:u.stop] if x is not None]
    assert [pt.text for pt in g["landmarks"]] == lm
    assert g.xmin == 0 and g.xmax == pytest.approx(u.n_frames / c.rate)


def test_textgrid_writer_fills_gaps_quotes_labels_and_refuses_overlaps(tmp_path):
    from engine.io.readers.alignment import _parse_textgrid

    tiers = [IntervalTier("words", [(0.1, 0.3, "hi"), (0.5, 0.7, "bye")]), PointTier("p", [(0.2, "x")])]
    p = write_textgrid(tmp_path / "a.TextGrid", 0, 1.0, tiers)
    g = _parse_textgrid(p)
    assert [(iv.xmin, iv.xmax, iv.text) for iv in g["words"]] == [
        (0, 0.1, ""), (0.1, 0.3, "hi"), (0.3, 0.5, ""), (0.5, 0.7, "bye"), (0.7, 1.0, "")]
    # a double quote doubled, as Praat writes it (praat-textgrids mangles it; Praat reads it: tests/cli)
    assert 'text = "say ""hi""" ' in textgrid_text(0, 1, [IntervalTier("w", [(0, 1, 'say "hi"')])])
    assert [(pt.xpos, pt.text) for pt in g["p"]] == [(0.2, "x")]
    assert textgrid_text(0, 1, [IntervalTier("e", [])]).count("intervals [") == 1  # one empty interval
    with pytest.raises(ValueError, match="before the previous one"):
        textgrid_text(0, 1, [IntervalTier("w", [(0.2, 0.5, "a"), (0.4, 0.6, "b")])])
    with pytest.raises(ValueError, match="xmin < xmax"):
        textgrid_text(1, 1, [])


def test_textgrid_names_are_file_names_and_unique():
    assert textgrid_names(["s1", "a/b", "A/B", "x:y", ".."]) == ["s1.TextGrid", "a_b.TextGrid", "A_B_2.TextGrid",
                                                                 "x_y.TextGrid", "utterance.TextGrid"]


def test_the_csv_quotes_only_what_needs_it_and_writes_na_for_missing(tmp_path):
    import csv

    from engine.io.writers.tidy import sidecar_path, write_frame_table
    from engine.manifold.frame_table import FrameTable

    t = FrameTable(columns={"phone": np.array(["a,b", 'say "x"', None, "two\nlines"], dtype=object),
                            "time_s": np.array([0.0, 1 / 60, np.nan, 2.5]), "frame": np.arange(4)},
                   units={"time_s": "s"}, descriptions={}, rate=60.0)
    paths = write_frame_table(tmp_path / "t.csv", t)
    assert paths == [tmp_path / "t.csv", sidecar_path(tmp_path / "t.csv")]
    with (tmp_path / "t.csv").open(encoding="utf-8", newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows == [["phone", "time_s", "frame"], ["a,b", "0", "0"], ['say "x"', "0.01666667", "1"], ["NA", "NA", "2"],
                    ["two\nlines", "2.5", "3"]]
    with pytest.raises(ValueError, match="ends in .csv or .parquet"):
        write_frame_table(tmp_path / "t.txt", t)

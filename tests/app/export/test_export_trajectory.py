"""The window's trajectory exports: a table as complete as ``lipspace synthesize``'s (point coordinates, phones,
units beside it) and a synthesised utterance as a TextGrid that Praat opens."""
from __future__ import annotations

import json

import numpy as np
import pytest


@pytest.fixture(scope="module")
def synthesis(app_manifold):
    """The editor's synthesis of an utterance's own phones (what File › Export writes after Synthesise)."""
    from app.models.trajectories import synthesize_targets
    from engine.phonetics.targets import targets_from_utterance

    m = app_manifold
    uid = m.corpus_.utterances[2].id
    targets = targets_from_utterance(m, uid, on_collision="merge")
    data, traj = synthesize_targets(m, targets, "linear")
    return m, uid, targets, data, traj


def test_the_csv_holds_points_phones_targets_and_units(synthesis, tmp_path):
    pd = pytest.importorskip("pandas")
    from app.export.trajectory import export_trajectory
    from engine.io.writers.export import corpus_columns

    m, uid, targets, data, traj = synthesis
    files = export_trajectory(m, data, tmp_path / "t.csv")
    assert [f.name for f in files] == ["t.csv", "t.csv.json"]
    d = pd.read_csv(tmp_path / "t.csv")
    c = m.corpus_
    assert len(d) == traj.n_frames
    points = corpus_columns(c)
    assert set(points) <= set(d.columns)  # every lip point's coordinates, named as synthesize -o names them
    np.testing.assert_allclose(d[points].to_numpy(), traj.frames(m), rtol=1e-5, atol=1e-4)
    assert {"time_s", "frame", "phone", "target", "lip_aperture", "y_1", "x_1"} <= set(d.columns)
    np.testing.assert_allclose(d["time_s"], np.arange(traj.n_frames) / targets.rate, rtol=1e-6)  # 7 digits
    labels = {p.label for p in targets.phones}
    assert set(d["phone"].dropna()) <= labels and d["phone"].notna().mean() > 0.5
    assert list(d["target"].dropna()) == [t for t in traj.target_labels]
    meta = json.loads((tmp_path / "t.csv.json").read_text())
    assert meta["columns"][points[0]]["unit"] == "mm" and meta["columns"]["time_s"]["unit"] == "s"
    assert meta["columns"]["y_1"]["unit"].startswith("embedding units")


def test_a_captured_utterance_exports_its_own_phones(synthesis, tmp_path):
    pd = pytest.importorskip("pandas")
    from app.export.trajectory import export_trajectory
    from app.models.state import original_trajectory

    m, uid, *_ = synthesis
    orig = original_trajectory(m, uid)
    export_trajectory(m, orig, tmp_path / "o.csv")
    d = pd.read_csv(tmp_path / "o.csv")
    u = m.corpus_.utterance(uid)
    assert len(d) == u.n_frames and set(d["utterance"]) == {uid}
    assert set(d["phone"].dropna()) == {p.label for p in u.phones}


def test_a_synthesis_exports_as_a_textgrid_praat_opens(synthesis, tmp_path, praat):
    from app.export.trajectory import export_textgrid
    from engine.io import read_textgrid

    m, uid, targets, data, traj = synthesis
    path = export_textgrid(m, data, tmp_path / "s.TextGrid")
    phones = read_textgrid(path, tier="phones")
    assert [(p.label) for p in phones] == [p.label for p in targets.phones]
    out = praat('tg = Read from file: "' + str(path) + '"\n'
                'n = Get number of tiers\nappendInfoLine: n\n'
                'for i to n\n  name$ = Get tier name: i\n  appendInfoLine: name$\nendfor\n')
    assert out.split() == ["3", "phones", "targets", "landmarks"]


def test_a_textgrid_needs_something_to_align(app_manifold, tmp_path):
    from app.export.trajectory import export_textgrid
    from app.models.state import TrajectoryData

    lone = TrajectoryData(Y=np.zeros((5, 3), np.float32), label="typed in")
    with pytest.raises(ValueError, match="nothing to align"):
        export_textgrid(app_manifold, lone, tmp_path / "x.TextGrid")
    with pytest.raises(ValueError, match="ends in .TextGrid"):
        export_textgrid(app_manifold, lone, tmp_path / "x.txt")

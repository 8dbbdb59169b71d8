"""A manifold without phone labels: the Phone clusters panel shows the four kinematic-landmark clusters, named as
landmarks (as `lipspace clusters` does), and fig3 calls its targets landmarks, not phones."""
from __future__ import annotations

import pytest

LANDMARKS = {"open", "closed", "opening", "closing"}


@pytest.fixture(scope="module")
def unlabelled(make_articulograph_manifold):
    m = make_articulograph_manifold(n_speakers=2, n_utterances=2, duration_s=(2.0, 2.0), seed=11, n_states=16)
    assert not any(u.phones for u in m.corpus_.utterances)
    return m


def test_the_state_clusters_kinematic_landmarks_as_lipspace_clusters_does(unlabelled, tmp_path, capsys):
    from app.cli import main
    from app.models.state import AppState

    s = AppState(unlabelled)
    rows = s.cluster_rows()
    assert s.cluster_kind == "kinematic" and {r["phone"] for r in rows} == LANDMARKS
    path = tmp_path / "m.npz"
    unlabelled.save(path)
    assert main(["clusters", str(path), "-q"]) == 0
    out = capsys.readouterr().out
    table = {ln.split()[0]: int(ln.split()[1]) for ln in out.splitlines()[3:] if ln.split()
             and ln.split()[0] in LANDMARKS}
    assert table == {r["phone"]: r["count"] for r in rows}


@pytest.mark.gui
def test_the_clusters_panel_shows_landmarks_named_as_landmarks(qapp, unlabelled):
    from app.models.state import AppState
    from app.views.clusters_panel import ClustersPanel

    s = AppState(unlabelled)
    panel = ClustersPanel(s)
    try:
        assert panel.table.rowCount() == 4
        assert panel.table.horizontalHeaderItem(0).text() == "Landmark"
        names = {panel.table.item(i, 0).text() for i in range(4)}
        assert names == LANDMARKS
        assert "kinematic landmarks" in panel.note.text() and "Tick a landmark" in panel.note.text()
        assert all("landmark" in r and "phone" not in r for r in panel.table_rows())
        from PySide6 import QtCore

        panel.table.item(0, 0).setCheckState(QtCore.Qt.CheckState.Checked)
        assert s.visible_phones == {panel.table.item(0, 0).text()}  # ticking shows its ellipsoid
    finally:
        panel.close_view()
        panel.deleteLater()


def test_fig3_calls_landmarks_landmarks(unlabelled):
    from app.figures import make_fig3
    from engine.recordings.kinematics import kinematic_if_unlabelled

    m = unlabelled
    corpus, _ = kinematic_if_unlabelled(m.corpus_)
    fig = make_fig3(_with_corpus(m, corpus))  # as lipspace figures labels a corpus without phones
    texts = [ax.title.get_text() for ax in fig.axes] + [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert any("kinematic landmark targets" in t for t in texts)
    assert {"open", "closed"} <= set(texts)  # the landmarks named in the legend by their kinds
    assert not any("phone" in t for t in texts), texts


def _with_corpus(m, corpus):
    import copy

    out = copy.copy(m)
    out.corpus_ = corpus
    return out

"""One build, any size: the exact / landmark switch and the K-means switch (issue 13)."""
import numpy as np
import pytest

from app.cli import main
from engine.manifold.buildplan import LANDMARKS_ABOVE, plan_build
from engine.manifold.model import Manifold


def test_plan_switches_exactly_at_the_threshold():
    assert plan_build(100, landmarks_above=100).n_landmarks is None
    above = plan_build(101, landmarks_above=100, default_landmarks=40)
    assert above.n_landmarks == 40 and "N > 100" in above.reason
    forced = plan_build(50, n_landmarks=30, landmarks_above=100)
    assert forced.n_landmarks == 30 and "--landmarks" in forced.reason
    assert plan_build(LANDMARKS_ABOVE).n_landmarks is None
    assert plan_build(LANDMARKS_ABOVE + 1).n_landmarks == 2000
    with pytest.raises(ValueError, match="landmarks_above"):
        plan_build(10, landmarks_above=0)


def test_plan_reports_minibatch_kmeans_above_its_size(monkeypatch):
    import engine.graph.states

    monkeypatch.setattr(engine.graph.states, "MINIBATCH_ABOVE", 500)
    assert not plan_build(500).minibatch_kmeans
    assert plan_build(501).minibatch_kmeans
    assert "mini-batch K-means" in plan_build(501).describe()


def test_states_use_minibatch_kmeans_above_the_size(monkeypatch, small_manifold):
    import sklearn.cluster

    import engine.graph.states

    used = []
    real = sklearn.cluster.MiniBatchKMeans

    def spy(**kw):
        used.append(kw["n_clusters"])
        return real(**kw)

    monkeypatch.setattr(sklearn.cluster, "MiniBatchKMeans", spy)  # imported by the fit, when it runs
    Fy, bounds = small_manifold.Fy_, small_manifold.corpus_.bounds
    engine.graph.states.StateGraph(n_states=50).fit(Fy, bounds)
    assert used == []
    monkeypatch.setattr(engine.graph.states, "MINIBATCH_ABOVE", len(Fy) - 1)
    g = engine.graph.states.StateGraph(n_states=50).fit(Fy, bounds)
    assert used == [50]
    assert g.adjacency_.format == "csr" and g.adjacency_.nnz < 50 * 50 / 2  # the graph stays sparse


def test_build_takes_the_landmark_path_above_the_threshold_and_says_so(tmp_path, capsys, small_manifold):
    out = tmp_path / "m.npz"
    assert small_manifold.embedding_.landmarks_ is None  # default threshold: exact at 4,500 frames
    assert main(["build", "--preset", "small", "-o", str(out), "-q", "--landmarks-above", "1000",
                 "--states", "40"]) == 0
    text = capsys.readouterr().out
    assert "embedding landmark (Nystrom, L=2000) (N > 1000 frames)" in text
    m = Manifold.load(out)
    assert m.embedding_.landmarks_.shape == (2000,) and m.landmarks_above == 1000
    # the landmark F^y spans nearly the same 3-D manifold as the exact one
    a, b = small_manifold.Fy_[:, :3].astype(np.float64), m.Fy_[:, :3].astype(np.float64)
    N = len(a)
    coef, *_ = np.linalg.lstsq(np.c_[b, np.ones(N)], a, rcond=None)
    resid = a - np.c_[b, np.ones(N)] @ coef
    assert (resid**2).sum() / ((a - a.mean(0)) ** 2).sum() < 0.02

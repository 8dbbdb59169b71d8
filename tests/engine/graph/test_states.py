"""StateGraph: K-means states, transition counts, directed hop distances (paper section 3.3).

Ground truth comes from the synthetic talker's manifold (consecutive frames are at
most one hop apart, distances are asymmetric) and from small hand-made graphs whose
states are well-separated point clouds, so K-means recovers them exactly and every
distance is known.
"""
import json

import numpy as np
import pytest
import scipy.sparse as sp

import engine.graph.states as states_mod
from engine.files.persist import dump_estimator, load_estimator
from engine.graph.states import StateGraph, StateGraphConnectivityWarning, UnreachableError, default_n_states
from engine.progress import Cancelled


def _in_utterance_pairs(labels, bounds):
    has_next = np.ones(len(labels), bool)
    has_next[np.asarray(bounds)[:, 1] - 1] = False
    return labels[:-1][has_next[:-1]], labels[1:][has_next[:-1]]


def _handmade(utterances, K, seed=0):
    """Frames visiting hand-chosen states (one tight cloud per state) -> (Fy, bounds, centres)."""
    rng = np.random.default_rng(seed)
    i = np.arange(K)
    centres = np.column_stack([10.0 * i, 6.0 * (i % 2), 4.0 * (i % 3)])
    seq = np.concatenate([np.asarray(u) for u in utterances])
    Fy = centres[seq] + 0.01 * rng.standard_normal((len(seq), 3))
    stops = np.cumsum([len(u) for u in utterances])
    bounds = np.column_stack([np.r_[0, stops[:-1]], stops])
    return Fy.astype(np.float32), bounds, centres


def _fit_handmade(utterances, K, **kw):
    Fy, bounds, centres = _handmade(utterances, K)
    g = StateGraph(n_states=K, **kw).fit(Fy, bounds)
    mine = g.predict(centres)  # engine state of each hand-made state
    assert sorted(mine) == list(range(K)), "K-means must recover the hand-made states"
    return g, mine


# ------------------------------------------------------------------ ground truth
@pytest.fixture(scope="module")
def graph(small_manifold):
    return small_manifold.states_


@pytest.fixture(scope="module")
def all_future(graph):
    K = graph.centroids_.shape[0]
    return np.vstack([graph.future(s) for s in range(K)])


def test_consecutive_frames_are_at_most_one_hop_apart(graph, small_manifold):
    bounds = small_manifold.corpus_.bounds
    a, b = _in_utterance_pairs(graph.labels_, bounds)
    move = a != b
    A = graph.adjacency_
    # vectorised over all in-utterance pairs: every change of state is an edge of A
    assert np.asarray(A[a[move], b[move]]).ravel().all()
    print(f"\n{len(a)} in-utterance transitions, {move.mean():.1%} change state; "
          f"{graph.centroids_.shape[0]} states, {A.nnz} edges")
    rng = np.random.default_rng(0)
    for i in rng.choice(len(a), size=40, replace=False):
        assert graph.future(int(a[i]))[b[i]] <= 1


def test_distances_are_directed_and_asymmetric(graph, all_future):
    D = all_future
    K = len(D)
    assert np.all(np.diag(D) == 0)
    finite = np.isfinite(D) & np.isfinite(D.T)
    asym = finite & (D != D.T)
    print(f"\n{asym.sum() // 2} of {K * (K - 1) // 2} state pairs have d(j,k) != d(k,j); "
          f"mean |d(j,k) - d(k,j)| {np.abs(D - D.T)[finite].mean():.2f} hops; "
          f"max distance {D[np.isfinite(D)].max():.0f}")
    assert asym.any()
    # every hop distance is an integer count of transitions
    assert np.all(D[np.isfinite(D)] == np.round(D[np.isfinite(D)]))


def test_hemispheres_point_along_the_motion(graph, all_future, small_manifold):
    # paper fig. 2(b): the states one hop ahead lie where the lips are going, the states one
    # hop behind where they came from (checks that A, not A^T, is the future)
    Fy, bounds = small_manifold.Fy_[:, :3].astype(np.float64), small_manifold.corpus_.bounds
    K = len(all_future)
    has_next = np.ones(len(Fy), bool)
    has_next[bounds[:, 1] - 1] = False
    i = np.flatnonzero(has_next)
    step = Fy[i + 1] - Fy[i]
    labels = graph.labels_
    outgoing = np.column_stack([np.bincount(labels[i], weights=step[:, j], minlength=K) for j in range(3)])
    incoming = np.column_stack([np.bincount(labels[i + 1], weights=step[:, j], minlength=K) for j in range(3)])

    def mean_offset(mask):
        return (mask.astype(np.float64) @ graph.centroids_) / np.maximum(mask.sum(axis=1), 1)[:, None] \
            - graph.centroids_

    def cos(p, q):
        return np.einsum("ij,ij->i", p, q) / (np.linalg.norm(p, axis=1) * np.linalg.norm(q, axis=1) + 1e-300)

    ahead, behind = all_future == 1, all_future.T == 1
    ok = ahead.any(axis=1) & behind.any(axis=1)
    fwd = (cos(mean_offset(ahead), outgoing)[ok] > 0).mean()
    bwd = (cos(mean_offset(behind), incoming)[ok] < 0).mean()
    print(f"\n1-hop future lies along the state's outgoing motion for {fwd:.1%} of states; "
          f"1-hop past lies against its incoming motion for {bwd:.1%}")
    assert fwd >= 0.8 and bwd >= 0.8


def test_past_is_future_over_the_transpose(graph, all_future):
    for s in np.random.default_rng(1).choice(len(all_future), size=10, replace=False):
        np.testing.assert_array_equal(graph.past(int(s)), all_future[:, s])
        f, p = graph.hemispheres(int(s))
        np.testing.assert_array_equal(f, all_future[s])
        np.testing.assert_array_equal(p, all_future[:, s])


def test_min_path_endpoints_and_adjacency(graph, all_future):
    rng = np.random.default_rng(2)
    A = graph.adjacency_.toarray()
    K = len(all_future)
    n_checked = 0
    for a, b in rng.integers(0, K, size=(60, 2)):
        if not np.isfinite(all_future[a, b]):
            with pytest.raises(UnreachableError):
                graph.min_path(int(a), int(b))
            continue
        path = graph.min_path(int(a), int(b))
        assert path[0] == a and path[-1] == b
        assert len(path) - 1 == all_future[a, b]
        assert np.all(A[path[:-1], path[1:]])
        n_checked += 1
    assert n_checked > 0
    assert list(graph.min_path(3, 3)) == [3]


def test_transition_matrix_and_counts(graph, small_manifold):
    bounds = small_manifold.corpus_.bounds
    a, b = _in_utterance_pairs(graph.labels_, bounds)
    K = graph.centroids_.shape[0]
    C = graph.counts_.toarray()
    assert C.sum() == len(a) == small_manifold.corpus_.n_frames - len(bounds)
    np.testing.assert_array_equal(C, np.bincount(a * K + b, minlength=K * K).reshape(K, K))
    P = graph.transition_
    assert sp.issparse(P)
    np.testing.assert_allclose(np.asarray(P.sum(axis=1)).ravel(), 1.0, atol=1e-12)
    out = C.sum(axis=1)
    live = out > 0
    np.testing.assert_allclose(P.toarray()[live], C[live] / out[live, None], atol=1e-12)
    Adense = graph.adjacency_.toarray()
    assert graph.adjacency_.dtype == bool and not Adense.diagonal().any()
    np.testing.assert_array_equal(Adense, (C > 0) & ~np.eye(K, dtype=bool))


def test_predict_reproduces_labels(graph, small_manifold):
    np.testing.assert_array_equal(graph.predict(small_manifold.Fy_), graph.labels_)
    assert graph.predict(small_manifold.Fy_[5]).shape == (1,)
    assert graph.labels_.dtype == np.int32


def test_given_centroids_give_the_fitted_graph_without_k_means(graph, small_manifold, monkeypatch):
    """A graph fitted before (a manifold file's centres) is rebuilt by assigning the frames to its centres."""
    def never(*a, **k):
        raise AssertionError("K-means ran")

    monkeypatch.setattr(StateGraph, "_kmeans", never)
    again = StateGraph(n_dims=graph.n_dims).fit(small_manifold.Fy_, small_manifold.corpus_.bounds,
                                                  centroids=graph.centroids_)
    np.testing.assert_array_equal(again.labels_, graph.labels_)
    assert (again.counts_ != graph.counts_).nnz == 0 and again.n_scc_ == graph.n_scc_
    with pytest.raises(ValueError, match="centroids must be a finite"):
        StateGraph(n_dims=graph.n_dims).fit(small_manifold.Fy_, small_manifold.corpus_.bounds,
                                             centroids=graph.centroids_[:, :2])


def test_connectivity_report_names_the_numbers(graph):
    rep = graph.connectivity_report()
    K = graph.centroids_.shape[0]
    assert f"{K} states" in rep and f"{graph.adjacency_.nnz} directed edges" in rep
    assert f"{graph.n_scc_} strongly connected component" in rep
    assert len(rep.splitlines()) == 3


# ------------------------------------------------------------ hand-made graphs
def test_cycle_distances_are_asymmetric():
    g, m = _fit_handmade([[0, 0, 1, 1, 2, 2, 3, 3, 0, 0, 1]], 4)
    assert g.n_scc_ == 1
    assert g.future(m[0])[m[1]] == 1 and g.future(m[1])[m[0]] == 3
    assert g.past(m[0])[m[1]] == 3
    np.testing.assert_array_equal(g.min_path(m[1], m[0]), m[[1, 2, 3, 0]])


def test_unreachable_is_infinite_and_warned():
    # utterance 1 ends in state 2, utterance 2 starts in state 3: no edge 2 -> 3 (bounds are not crossed)
    Fy, bounds, centres = _handmade([[0, 0, 1, 1, 2], [3, 3, 2]], 4)
    with pytest.warns(StateGraphConnectivityWarning, match="4 strongly connected components") as rec:
        g = StateGraph(n_states=4).fit(Fy, bounds)
    print("\n" + str(rec[0].message))
    m = g.predict(centres)
    f = g.future(m[0])
    np.testing.assert_array_equal(f[m], [0, 1, 2, np.inf])
    np.testing.assert_array_equal(g.past(m[2])[m], [2, 1, 0, 1])
    assert not g.adjacency_[m[2], m[3]]
    assert g.counts_.sum() == 6
    with pytest.raises(UnreachableError, match=rf"state {m[0]} is unreachable from state {m[2]}") as exc:
        g.min_path(m[2], m[0])
    assert isinstance(exc.value, ValueError)
    np.testing.assert_array_equal(g.min_path(m[0], m[2]), m[[0, 1, 2]])
    # state 2 has no outgoing transition: absorbing in P, absent from A
    P = g.transition_.toarray()
    assert P[m[2], m[2]] == 1.0 and P[m[0], m[0]] == 0.5 and P[m[0], m[1]] == 0.5
    rep = g.connectivity_report()
    assert "4 strongly connected components" in rep and "1 with no outgoing transition" in rep
    print(rep)


def test_duplicate_frames_drop_empty_states():
    Fy = np.repeat(np.array([[0.0, 0, 0], [5, 0, 0], [0, 5, 0]], np.float32), 10, axis=0)
    bounds = np.array([[0, 15], [15, 30]])
    with pytest.warns(StateGraphConnectivityWarning):
        g = StateGraph(n_states=6).fit(Fy, bounds)
    assert g.centroids_.shape == (3, 3)
    assert set(np.unique(g.labels_)) == {0, 1, 2}
    np.testing.assert_array_equal(g.predict(Fy), g.labels_)


def test_minibatch_branch(monkeypatch):
    monkeypatch.setattr(states_mod, "MINIBATCH_ABOVE", 50)
    utts = [[0, 1, 2, 3, 4, 5, 0, 1, 2]] * 8
    g, m = _fit_handmade(utts, 6, batch_size=48)
    assert g.n_scc_ == 1 and g.future(m[0])[m[5]] == 5 and g.future(m[5])[m[0]] == 1


def test_minibatch_centroids_from_a_subset_every_frame_assigned(monkeypatch):
    """Above KMEANS_FIT_FRAMES the centroids come from that many frames (the same ones for the same
    random_state) and every frame still gets the nearest centroid's label."""
    from sklearn.cluster import MiniBatchKMeans

    monkeypatch.setattr(states_mod, "MINIBATCH_ABOVE", 50)
    monkeypatch.setattr(states_mod, "KMEANS_FIT_FRAMES", 150)
    seen = []
    fit = MiniBatchKMeans.fit
    monkeypatch.setattr(MiniBatchKMeans, "fit",
                        lambda self, X, *a, **k: (seen.append(len(X)), fit(self, X, *a, **k))[1])
    utts = [[0, 1, 2, 3, 4, 5, 0, 1, 2]] * 40  # 360 frames of 6 handmade states
    g, m = _fit_handmade(utts, 6, batch_size=48)
    assert seen == [150]
    Fy, bounds, _ = _handmade(utts, 6)
    np.testing.assert_array_equal(g.predict(Fy), g.labels_)  # all 360 frames assigned to their nearest state
    assert len(np.unique(g.labels_)) == 6 and g.future(m[0])[m[5]] == 5
    g2, _ = _fit_handmade(utts, 6, batch_size=48)
    np.testing.assert_array_equal(g2.centroids_, g.centroids_)  # the same subset for the same random_state


def test_default_number_of_states():
    assert default_n_states(4500) == 150
    assert default_n_states(28833) == 961
    assert default_n_states(10) == 2 and default_n_states(1) == 1
    assert default_n_states(10**6) == 3000
    Fy, bounds, _ = _handmade([list(range(8)) * 2] * 5, 8)
    g = StateGraph().fit(Fy, bounds)
    assert g.centroids_.shape[0] == default_n_states(len(Fy)) == 3  # round(80 / 30)


def test_progress_and_cancel():
    Fy, bounds, _ = _handmade([[0, 1, 2, 0]] * 5, 3)
    calls = []
    StateGraph(n_states=3).fit(Fy, bounds, progress=lambda *a: calls.append(a))
    assert calls[0] == ("state graph", 0, 3) and calls[-1] == ("state graph", 3, 3)

    for at in (1, 3):
        def cancel(stage, done, total, at=at):
            if done == at:
                raise Cancelled()

        g = StateGraph(n_states=3)
        with pytest.raises(Cancelled):
            g.fit(Fy, bounds, progress=cancel)
        assert not hasattr(g, "labels_") and not hasattr(g, "adjacency_")


def test_saved_and_loaded_graph_answers_queries(graph):
    d = dump_estimator(graph, "states")
    g2 = load_estimator(StateGraph, d, "states")
    for s in (0, 7):
        np.testing.assert_array_equal(g2.future(s), graph.future(s))
        np.testing.assert_array_equal(g2.past(s), graph.past(s))
    far = int(np.argmax(np.where(np.isfinite(graph.future(0)), graph.future(0), -1)))
    np.testing.assert_array_equal(g2.min_path(0, far), graph.min_path(0, far))
    assert g2.connectivity_report() == graph.connectivity_report()


def test_a_loaded_graph_makes_its_csr_matrices_on_first_use(graph):
    """Read back, the csr attributes wait as their saved arrays (no SciPy needed to load a manifold); each is
    made, equal to the fitted one, when first used; saving again writes the same arrays; a refit drops them."""
    d = dump_estimator(graph, "states")
    g2 = load_estimator(StateGraph, d, "states")
    assert sorted(g2.__dict__["_csr_parts"]) == ["adjacency_", "counts_", "transition_"]
    assert "adjacency_" not in vars(g2)
    A = g2.adjacency_
    assert sp.issparse(A) and A.format == "csr" and "adjacency_" in vars(g2)
    assert (A != graph.adjacency_).nnz == 0 and g2.adjacency_ is A  # made once, then kept
    assert sorted(g2.__dict__["_csr_parts"]) == ["counts_", "transition_"]
    d2 = dump_estimator(g2, "states")  # the ones never used are written too
    assert sorted(d2) == sorted(d)
    for key in d:
        if key.endswith("__kinds__"):  # the same kinds (those made on use are listed last)
            assert json.loads(str(d2[key])) == json.loads(str(d[key]))
        else:
            np.testing.assert_array_equal(np.asarray(d2[key]), np.asarray(d[key]), err_msg=key)
    with pytest.raises(AttributeError, match="no attribute 'nothing_'"):
        g2.nothing_  # noqa: B018 - an attribute neither set nor saved is still missing
    g3 = load_estimator(StateGraph, d, "states")
    g3.__dict__["counts_"] = graph.counts_  # made by another thread between the lookup and the part's use
    del g3.__dict__["_csr_parts"]["counts_"]
    assert g3.__getattr__("counts_") is graph.counts_
    g4 = load_estimator(StateGraph, dump_estimator(_fit_handmade([[0, 0, 1, 1, 2, 2, 0]], 3)[0], "s"), "s")
    Fy, bounds, _centres = _handmade([[0, 0, 1, 1, 2, 2, 3, 3, 0]], 4)
    g4.set_params(n_states=4).fit(Fy, bounds)  # a refit: the 3-state file's arrays must not come back
    assert "_csr_parts" not in vars(g4) and g4.adjacency_.shape == (4, 4) and g4.counts_.shape == (4, 4)


# ------------------------------------------------------------------ bad input
def test_bad_input_is_rejected_with_the_fix():
    Fy, bounds, _ = _handmade([[0, 1, 2, 0, 1, 2]], 3)
    with pytest.raises(ValueError, match=r"n_states must be an integer in 1..N = 1..6"):
        StateGraph(n_states=7).fit(Fy, bounds)
    with pytest.raises(ValueError, match="n_states"):
        StateGraph(n_states=0).fit(Fy, bounds)
    with pytest.raises(ValueError, match=r"at least n_dims=3 columns, got shape \(6, 2\)"):
        StateGraph(n_states=2).fit(Fy[:, :2], bounds)
    bad = Fy.copy()
    bad[4, 1] = np.nan
    with pytest.raises(ValueError, match="NaN or infinite values \\(first at frame 4\\)"):
        StateGraph(n_states=2).fit(bad, bounds)
    with pytest.raises(ValueError, match="bounds"):
        StateGraph(n_states=2).fit(Fy, [[0, 5]])
    with pytest.raises(ValueError, match="batch_size"):
        StateGraph(n_states=2, batch_size=0).fit(Fy, bounds)
    g = StateGraph(n_states=3).fit(Fy, bounds)
    with pytest.raises(ValueError, match=r"state=3 is out of range: the graph has 3 states \(0..2\)"):
        g.future(3)
    with pytest.raises(ValueError, match="b=-1 is out of range"):
        g.min_path(0, -1)
    with pytest.raises(TypeError, match="integer state index"):
        g.past(1.5)
    with pytest.raises(ValueError, match="at least n_dims=3"):
        g.predict(np.zeros((4, 2)))

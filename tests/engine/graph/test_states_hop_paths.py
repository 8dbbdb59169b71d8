"""Fewest-hop state paths by bidirectional search (engine.graph.hop_paths, StateGraph.min_path; issue 13 item 8).

References: scipy's Dijkstra (unit weights) for the number of hops and unreachability,
scipy's breadth-first search from ``a`` (the previous implementation of ``min_path``)
for which path is returned among ties, and, on tiny graphs, every simple path
enumerated by brute force for the claim that this is the lexicographically smallest.
"""
import itertools

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, dijkstra

from engine.graph.hop_paths import fewest_hop_path, hop_distances
from engine.graph.states import UnreachableError


def _bfs_tree_path(G, a, b):
    """The path of the predecessor tree of a breadth-first search from a (None: unreachable)."""
    if a == b:
        return np.array([a])
    pred = breadth_first_order(G, a, directed=True, return_predecessors=True)[1]
    if pred[b] < 0:
        return None
    path = [b]
    while path[-1] != a:
        path.append(int(pred[path[-1]]))
    return np.array(path[::-1])


def _graph(K, n_edges, rng, *, sink_block=0):
    """Random directed graph (csr, sorted, no self-loops) and its transpose; the last
    ``sink_block`` nodes have edges only among themselves (unreachable from the rest)."""
    src = rng.integers(0, K, n_edges)
    dst = rng.integers(0, K, n_edges)
    if sink_block:
        inside = src >= K - sink_block
        dst = np.where(inside, rng.integers(K - sink_block, K, n_edges), dst % (K - sink_block))
    keep = src != dst
    G = sp.csr_matrix((np.ones(keep.sum()), (src[keep], dst[keep])), shape=(K, K))
    G.sum_duplicates()
    G.sort_indices()
    GT = sp.csr_matrix(G.T)
    GT.sort_indices()
    return G, GT


@pytest.mark.parametrize("K, degree, sink", [(30, 2.5, 0), (60, 3.0, 10), (200, 4.0, 0), (400, 8.0, 40)])
def test_paths_match_dijkstra_and_breadth_first_tree_on_random_graphs(K, degree, sink):
    rng = np.random.default_rng(K)
    G, GT = _graph(K, int(K * degree), rng, sink_block=sink)
    hops = dijkstra(G, directed=True, unweighted=True)
    A = G.toarray() > 0
    n_paths = n_ties = n_none = 0
    for a in rng.choice(K, size=min(K, 12), replace=False):
        a = int(a)
        tree = breadth_first_order(G, a, directed=True, return_predecessors=True)[1]
        for b in map(int, rng.choice(K, size=min(K, 40), replace=False)):
            got = fewest_hop_path(G, GT, a, b)
            if not np.isfinite(hops[a, b]):
                assert got is None, (a, b)
                n_none += 1
                continue
            assert got.dtype == np.int64 and got[0] == a and got[-1] == b
            assert len(got) - 1 == hops[a, b], (a, b)
            assert A[got[:-1], got[1:]].all(), "every hop is an edge"
            want = [b]
            while want[-1] != a:
                want.append(int(tree[want[-1]]))
            np.testing.assert_array_equal(got, want[::-1])
            n_paths += 1
            if b != a:  # several fewest-hop predecessors: a tie the search had to break
                n_ties += int(((hops[a] == hops[a, b] - 1) & A[:, b]).sum() > 1)
    assert n_paths > 100 and n_ties > 5, (n_paths, n_ties)
    assert (n_none > 0) == (sink > 0 or not np.isfinite(hops).all())


def test_tie_broken_to_the_lexicographically_smallest_path_by_brute_force():
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(15):
        K = 7
        G, GT = _graph(K, 16, rng)
        A = G.toarray() > 0
        for a, b in itertools.permutations(range(K), 2):
            walks = [p for n in range(K - 1) for p in itertools.permutations(set(range(K)) - {a, b}, n)
                     if all(A[x, y] for x, y in zip((a,) + p, p + (b,)))]
            got = fewest_hop_path(G, GT, a, b)
            if not walks:
                assert got is None
                continue
            fewest = min(len(p) for p in walks)
            best = min((a,) + p + (b,) for p in walks if len(p) == fewest)
            assert tuple(got) == best
            checked += 1
    assert checked > 50


def test_same_node_and_unsorted_rows():
    G, GT = _graph(10, 30, np.random.default_rng(1))
    np.testing.assert_array_equal(fewest_hop_path(G, GT, 4, 4), [4])
    with pytest.raises(ValueError, match=r"b=10 is out of range: the graph has 10 nodes \(0..9\)"):
        fewest_hop_path(G, GT, 0, 10)
    U = G.copy()
    U.indices = U.indices.copy()
    for i in range(U.shape[0]):  # reverse each row: still the same graph, rows no longer sorted
        lo, hi = U.indptr[i], U.indptr[i + 1]
        U.indices[lo:hi] = U.indices[lo:hi][::-1]
    U.has_sorted_indices = False
    if (np.diff(U.indptr) > 1).any():
        with pytest.raises(ValueError, match="sorted indices"):
            fewest_hop_path(U, GT, 0, 5)


def test_state_graph_min_path_is_the_breadth_first_tree_path(small_manifold):
    g = small_manifold.states_
    G = g._graph(False)
    K = g.centroids_.shape[0]
    hops = dijkstra(G, directed=True, unweighted=True)
    rng = np.random.default_rng(3)
    for a, b in rng.integers(0, K, size=(150, 2)):
        want = _bfs_tree_path(G, int(a), int(b))
        if want is None:
            with pytest.raises(UnreachableError, match=f"state {b} is unreachable from state {a}"):
                g.min_path(int(a), int(b))
            continue
        got = g.min_path(int(a), int(b))
        np.testing.assert_array_equal(got, want)
        assert len(got) - 1 == hops[a, b]


def test_prepare_queries_builds_the_cached_graphs_queries_then_use(small_manifold):
    from engine.files.persist import dump_estimator, load_estimator
    from engine.graph.states import StateGraph

    g = load_estimator(StateGraph, dump_estimator(small_manifold.states_, "states"), "states")  # a fresh cache
    assert not g.__dict__.get("_cache")
    assert g.prepare_queries() is g
    A, AT = g._cache["A"], g._cache["AT"]
    assert A.has_sorted_indices and AT.has_sorted_indices
    np.testing.assert_array_equal(A.toarray(), g.adjacency_.toarray())
    np.testing.assert_array_equal(AT.toarray(), g.adjacency_.toarray().T)
    K = g.centroids_.shape[0]
    a, b = 0, K - 1
    fut = g.future(a)
    if np.isfinite(fut[b]):
        assert len(g.min_path(a, b)) - 1 == fut[b]
    assert g._cache["A"] is A and g._cache["AT"] is AT  # the queries used them, built nothing new


def test_hop_distances_equal_dijkstra_with_unit_weights():
    """The breadth-first hop counts behind future/past are Dijkstra's, inf where unreachable (issue 13 item 8)."""
    rng = np.random.default_rng(4)
    K = 400
    src, dst = rng.integers(0, K - 20, 2400), rng.integers(0, K - 20, 2400)  # the last 20 states: no edge in
    chain = np.arange(K - 20, K - 1)  # ... except a chain among themselves, reachable only from its head
    A = sp.csr_matrix((np.ones(2400 + len(chain)), (np.r_[src, chain], np.r_[dst, chain + 1])), shape=(K, K))
    for s in [0, 7, K - 20, K - 1]:
        want = dijkstra(A, directed=True, indices=s, unweighted=True)
        got = hop_distances(A, s)
        np.testing.assert_array_equal(got, want)
    assert np.isinf(hop_distances(A, 0)[K - 20:]).all() and hop_distances(A, K - 20)[K - 1] == 19


def test_grown_balls_hold_the_hop_distances_and_grow_the_cheaper_side():
    """grow_balls (shared by min_path and the synthesis bridges): after each level, the balls hold exactly the
    states within their radius of a (forward) and of b (backward), and the ball grown had the frontier with
    fewer edges to follow."""
    from engine.graph.hop_paths import csr_rows, grow_balls

    rng = np.random.default_rng(7)
    K = 300
    A = sp.csr_matrix((np.ones(900), (rng.integers(0, K, 900), rng.integers(0, K, 900))), shape=(K, K))
    AT = A.T.tocsr()
    a, b = 3, 250
    want_a, want_b = hop_distances(A, a), hop_distances(AT, b)
    da, db = np.full(K, -1, np.int32), np.full(K, -1, np.int32)
    da[a], db[b] = 0, 0
    fronts = {True: np.array([a]), False: np.array([b])}
    out_n, in_n = np.diff(A.indptr), np.diff(AT.indptr)
    sides = []
    for ka, kb, forward_grew, front in grow_balls(csr_rows(A), csr_rows(AT), da, db, fronts[True], fronts[False]):
        cost_a = out_n[fronts[True]].sum() if fronts[True].size else np.inf
        cost_b = in_n[fronts[False]].sum() if fronts[False].size else np.inf
        assert forward_grew == (cost_a <= cost_b)
        fronts[forward_grew] = front
        sides.append(forward_grew)
        for d, want, k in ((da, want_a, ka), (db, want_b, kb)):
            inside = want <= k
            np.testing.assert_array_equal(d[inside], want[inside])
            assert (d[~inside] == -1).all()
        if ka + kb == 12:
            break
    assert any(sides) and not all(sides)  # both balls grew


def test_many_fewest_hop_paths_do_not_multiply_the_work(monkeypatch):
    """Layers of 4 states, each joined to every state of the next: 4^9 fewest-hop paths from a to b. Rebuilding
    the path reads each state of the forward ball at most once per level (it used to read a state once per path
    through it, which grows as 4^level and ran out of memory on dense graphs)."""
    import engine.graph.hop_paths as hp

    w, L = 4, 10
    K = w * L + 2
    a, b = 0, K - 1
    layer = [np.array([a])] + [1 + w * i + np.arange(w) for i in range(L)] + [np.array([b])]
    edges = np.array([(u, v) for x, y in zip(layer[:-1], layer[1:]) for u in x for v in y])
    G = sp.csr_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(K, K))
    G.sort_indices()
    GT = G.T.tocsr()
    GT.sort_indices()
    read = []
    real = hp._next
    monkeypatch.setattr(hp, "_next", lambda M, nodes: read.append(len(nodes)) or real(M, nodes))
    path = hp.fewest_hop_path(G, GT, a, b)
    np.testing.assert_array_equal(path, _bfs_tree_path(G, a, b))
    assert len(path) == L + 2 and read and max(read) <= w

"""Exact-length Viterbi paths over the balls around their ends (engine.graph.bridges; issue 13 item 8).

The reference is the full recursion, :meth:`MaxProductGraph.viterbi` over every edge at
every step, then :meth:`MaxProductGraph.backtrack`: same paths (ties included), same
scores at the targets, and None exactly where the full recursion finds no path.
"""
import numpy as np
import pytest
import scipy.sparse as sp

from engine.graph.bridges import bridge, forward_to
from engine.synthesis.viterbi import MaxProductGraph, log_transitions, observed_transitions


class _Counts:
    def __init__(self, C):
        self.counts_ = C


def _random_graph(rng, K, n_edges, *, ties):
    src, dst = rng.integers(0, K, n_edges), rng.integers(0, K, n_edges)
    w = np.ones(n_edges) if ties else rng.integers(1, 5, n_edges).astype(float)
    C = sp.csr_matrix((w, (src, dst)), shape=(K, K))
    return MaxProductGraph(log_transitions(observed_transitions(_Counts(C))))


def _full(g, a, b, n):
    scores, hist = g.viterbi(a, n)
    return g.backtrack(hist, b) if np.isfinite(scores[b]) else None


@pytest.mark.parametrize("ties", [False, True])
def test_bridge_and_forward_to_equal_the_full_recursion_on_random_graphs(ties):
    rng = np.random.default_rng(11 + ties)
    found = missing = 0
    for _ in range(40):
        K = int(rng.integers(2, 40))
        g = _random_graph(rng, K, int(rng.integers(1, 4 * K)), ties=ties)
        for _ in range(10):
            a, b = (int(x) for x in rng.integers(0, K, 2))
            n = int(rng.integers(1, 10))
            want, got = _full(g, a, b, n), bridge(g, a, b, n)
            if want is None:
                assert got is None, (a, b, n)
                missing += 1
            else:
                assert got.dtype == np.int64
                np.testing.assert_array_equal(got, want)
                found += 1
            S = rng.choice(K, size=min(K, 3), replace=False)
            T = rng.choice(K, size=min(K, 4), replace=False)
            np.testing.assert_array_equal(forward_to(g, S, n, T), g.forward(S, n)[:, T])
    assert found > 100 and missing > 100, (found, missing)


def test_bridge_equals_the_full_recursion_on_a_fitted_state_graph(small_manifold):
    st = small_manifold.states_
    g = MaxProductGraph(log_transitions(observed_transitions(st)))
    lab = np.asarray(st.labels_)
    rng = np.random.default_rng(5)
    found = 0
    for f0 in rng.integers(0, len(lab) - 30, 40):
        for n in (2, 5, 9, 16):
            a, b = int(lab[f0]), int(lab[f0 + n - 1])
            want = _full(g, a, b, n)
            got = bridge(g, a, b, n)
            if want is None:
                assert got is None
                continue
            np.testing.assert_array_equal(got, want)
            found += 1
        targets = lab[f0: f0 + 28: 7]
        np.testing.assert_array_equal(forward_to(g, targets[:-1], 8, targets[1:]),
                                      g.forward(targets[:-1], 8)[:, targets[1:]])
    assert found > 100


def test_synthesis_paths_unchanged(small_manifold):
    """ViterbiSynthesizer's state path is the gap-by-gap full Viterbi path (strict and not)."""
    from engine.phonetics.targets import Target, TargetSequence
    from engine.synthesis.viterbi import ViterbiSynthesizer

    st = small_manifold.states_
    lab = np.asarray(st.labels_)
    syn = ViterbiSynthesizer(strict=False, inverse="state-mean").fit(small_manifold)
    g = syn._graph
    rng = np.random.default_rng(8)
    compared = 0
    for f0 in rng.integers(0, len(lab) - 60, 6):
        frames = np.array([0, 4, 9, 11, 20, 31, 33])  # gaps of 5, 6, 3, 10, 12 and 3 frames
        states = [int(lab[f0 + 2 * k]) for k in range(len(frames))]  # not always bridgeable in time
        ts = TargetSequence(tuple(Target(int(fr), "", s, None, None) for fr, s in zip(frames, states)), (),
                            int(frames[-1]) + 3, small_manifold.corpus_.rate, "test")
        got = syn.synthesize(ts).states
        cur = states[0]
        for i in range(len(frames) - 1):
            n = int(frames[i + 1] - frames[i] + 1)
            scores, hist = g.viterbi(cur, n)
            end = states[i + 1]
            if np.isfinite(scores[end]):
                np.testing.assert_array_equal(got[frames[i]: frames[i + 1] + 1], g.backtrack(hist, end))
                compared += 1
            cur = int(got[frames[i + 1]])
    assert compared > 15


def test_out_of_range_states_and_lengths_are_refused():
    g = _random_graph(np.random.default_rng(2), 6, 20, ties=False)
    with pytest.raises(ValueError, match=r"state 6 is out of range: the graph has 6 states \(0..5\)"):
        bridge(g, 0, 6, 3)
    with pytest.raises(ValueError, match="state -1 is out of range"):
        forward_to(g, [0, -1], 3, [1])
    with pytest.raises(ValueError, match="at least 1 frame, got n=0"):
        bridge(g, 0, 0, 0)

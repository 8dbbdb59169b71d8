"""engine.graph.hemispheres: hops within a time horizon and the hemispheres they bound."""
from __future__ import annotations

import numpy as np
import pytest

from engine.graph.hemispheres import hemisphere, horizon_hops, horizon_seconds


class ChainGraph:
    """A directed chain 0 -> 1 -> ... -> K-1 plus an isolated last state (a StateGraph's two queries)."""

    def __init__(self, K):
        self.K = K

    def future(self, s):
        d = np.full(self.K, np.inf)
        d[s:self.K - 1] = np.arange(self.K - 1 - s)
        if s == self.K - 1:
            d[s] = 0
        return d

    def past(self, s):
        d = np.full(self.K, np.inf)
        if s == self.K - 1:
            d[s] = 0
            return d
        d[:s + 1] = np.arange(s, -1, -1)
        return d


def test_horizon_hops_at_the_frame_rate():
    assert horizon_hops(0.1, 60) == 6           # 100 ms at 60 frames/s: 6 frame steps
    assert horizon_hops(0.1, 100) == 10
    assert horizon_hops(0.05, 60) == 3          # exactly 3 frames: the tolerance keeps 3, not 2
    assert horizon_hops(0.016, 60) == 0         # shorter than a frame: only the state itself
    assert horizon_hops(horizon_seconds(7, 60), 60) == 7
    with pytest.raises(ValueError, match="seconds >= 0"):
        horizon_hops(-0.1, 60)
    with pytest.raises(ValueError, match="frame rate"):
        horizon_hops(0.1, 0)


def test_hemisphere_within_a_horizon_on_a_chain():
    g = ChainGraph(10)                       # states 0..8 a chain, 9 isolated
    labels = np.repeat(np.arange(10), 2)     # two frames per state
    h = hemisphere(g, 3, labels, direction="future", max_hops=2)
    np.testing.assert_array_equal(h.hops[::2], [np.nan] * 3 + [0, 1, 2] + [np.nan] * 4)
    assert h.n_inside == 6 and h.fraction_inside == pytest.approx(6 / 20)
    assert h.reach == 5                      # 3 -> 8
    np.testing.assert_array_equal(h.reachable[::2], [False] * 3 + [True] * 6 + [False])
    p = hemisphere(g, 3, labels, direction="past", max_hops=None)
    np.testing.assert_array_equal(p.hops[::2], [-3, -2, -1, 0] + [np.nan] * 6)
    b = hemisphere(g, 3, labels, direction="both", max_hops=1)
    np.testing.assert_array_equal(b.hops[::2], [np.nan, np.nan, -1, 0, 1] + [np.nan] * 5)
    assert b.fraction_inside == pytest.approx(6 / 20)
    with pytest.raises(ValueError, match="whole number"):
        hemisphere(g, 3, labels, max_hops=1.5)
    with pytest.raises(ValueError, match="direction"):
        hemisphere(g, 3, labels, direction="sideways")


def test_hemisphere_separates_on_a_strongly_connected_manifold(small_manifold):
    m = small_manifold
    g, lab = m.states_, m.states_.labels_
    s = int(lab[300])
    full = hemisphere(g, s, lab, direction="future")
    near = hemisphere(g, s, lab, direction="future", max_hops=2)
    # inside the horizon = exactly the frames whose state is at most 2 directed hops away
    d = g.future(s)[lab]
    np.testing.assert_array_equal(near.inside, d <= 2)
    assert near.fraction_inside < full.fraction_inside
    assert np.nanmax(near.hops) <= 2 and np.nanmin(near.hops) == 0

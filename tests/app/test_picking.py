"""From a picked point to a frame, then to the state: each layer alone (no display)."""
from __future__ import annotations

import numpy as np
import pytest

from app.picking import PointLocator, handle_pick, pick_to_frame
from app.state import AppState


def test_pick_to_frame_nearest_point():
    rng = np.random.default_rng(1)
    Y = rng.normal(size=(500, 3))
    for i in (0, 17, 499):
        assert pick_to_frame(Y[i] + 1e-4, Y) == i
    brute = int(np.argmin(((Y - [0.3, -0.2, 0.1]) ** 2).sum(1)))
    assert pick_to_frame([0.3, -0.2, 0.1], Y) == brute
    assert pick_to_frame(np.int64(42), Y) == 42  # a VTK point id passes through


def test_pick_to_frame_rejects_bad_input():
    Y = np.zeros((4, 3))
    with pytest.raises(IndexError, match="out of range"):
        pick_to_frame(4, Y)
    with pytest.raises(ValueError, match="3 finite"):
        pick_to_frame([0, np.nan, 0], Y)
    with pytest.raises(ValueError, match="shape"):
        pick_to_frame([0, 0, 0], np.zeros((4, 2)))


def test_point_locator_matches_brute_force():
    rng = np.random.default_rng(2)
    Y = rng.normal(size=(2000, 3))
    loc = PointLocator(Y)
    for q in rng.normal(size=(20, 3)):
        assert loc(q) == pick_to_frame(q, Y)
    assert loc(7) == 7


def test_handle_pick_selects_frame_and_target(app_manifold):
    m = app_manifold
    Y3 = m.Fy_[:, :3]
    s = AppState(m)
    loc = PointLocator(Y3)
    i = handle_pick(s, Y3[321] + 1e-6, loc)
    assert np.allclose(Y3[i], Y3[321]) and s.frame == i
    assert s.state == int(m.states_.labels_[i])
    other = int(np.flatnonzero(m.states_.labels_ != s.state)[0])
    handle_pick(s, other, loc, as_target=True)  # shift-click
    assert s.frame == i and s.target == int(m.states_.labels_[other])

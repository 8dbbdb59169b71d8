"""From a picked point to a frame, then to the state: each layer alone (no display)."""
from __future__ import annotations

import numpy as np
import pytest

from app.models.picking import PointLocator, handle_pick, pick_to_frame
from app.models.state import AppState


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


# ----------------------------------------------------------------- the frame under the cursor, among all frames
def test_frame_under_cursor_takes_the_front_dot_then_the_nearest():
    from app.models.picking import frame_under_cursor

    xy = np.array([[10.0, 10.0], [10.5, 10.0], [14.0, 10.0], [30.0, 30.0]])
    depth = np.array([0.5, 0.2, 0.0, 2.0])  # the last one is outside the view volume
    # both 0 and 1 cover the cursor: the nearer the camera (1) is drawn over the other
    assert frame_under_cursor(xy, depth, (10.2, 10.0), dot_radius=1.75, radius=6) == 1
    # no dot covers the cursor: the nearest centre within the tolerance
    assert frame_under_cursor(xy, depth, (12.6, 10.0), dot_radius=1.0, radius=6) == 2
    assert frame_under_cursor(xy, depth, (30.0, 30.0), dot_radius=1.75, radius=6) is None  # not in view
    assert frame_under_cursor(xy, depth, (60.0, 60.0), dot_radius=1.75, radius=6) is None


def _lod_view(N, cap, seed):
    """A level-of-detail cloud and a real camera's projection of it (off-screen)."""
    pv = pytest.importorskip("pyvista")
    from app.models.lod import cloud_detail
    from app.scene.projection import view_transform

    rng = np.random.default_rng(seed)
    Y = np.cumsum(rng.normal(size=(N, 3)) * 0.05, axis=0)  # a trajectory-like cloud: dense, overlapping
    labels = (np.arange(N) * 97 // N) % 31
    cd = cloud_detail(Y, labels, max_points=cap)
    p = pv.Plotter(off_screen=True, window_size=(400, 300))
    try:
        p.add_points(Y[cd.frames].astype(np.float32))
        p.reset_camera()
        p.camera.zoom(1.6)  # part of the cloud leaves the view, part comes close to the camera
        p.render()
        M, size = view_transform(p)
    finally:
        p.close()
    return Y, cd, M, size


@pytest.mark.parametrize("N, cap", [(30000, 2500), (3000, 5000)])
def test_cloud_locator_finds_what_a_search_over_every_frame_finds(N, cap):
    """The frame a click selects is the one :func:`frame_under_cursor` chooses among *every* frame, also
    frames the level of detail does not draw; and a click on a frame's own position never selects a frame
    behind it."""
    from app.models.picking import CloudLocator, frame_under_cursor
    from app.scene.projection import project

    Y, cd, M, size = _lod_view(N, cap, seed=4)
    loc = CloudLocator(Y, cd, dot_radius=1.75, radius=6.0)
    xy, depth = project(Y, M, size)
    rng = np.random.default_rng(5)
    seen = np.flatnonzero((np.abs(depth) <= 1) & (xy[:, 0] >= 0) & (xy[:, 0] < size[0]) & (xy[:, 1] >= 0)
                          & (xy[:, 1] < size[1]))
    clicks = np.vstack([xy[rng.choice(seen, 80)], rng.uniform((0, 0), size, (80, 2))])
    hits = 0
    for mouse in clicks:
        want = frame_under_cursor(xy, depth, mouse, dot_radius=1.75, radius=6.0)
        got = loc.locate(mouse, M, size)
        assert got == want, (mouse, got, want)
        hits += got is not None
        assert loc.n_candidates <= N
    assert hits > 80
    if not cd.whole:
        assert np.mean([len(loc.candidates(m, M, size)) for m in clicks[:20]]) < 0.2 * N  # not a scan of all


def test_handle_pick_takes_a_located_frame(app_manifold):
    s = AppState(app_manifold)
    assert handle_pick(s, 123) == 123 and s.frame == 123

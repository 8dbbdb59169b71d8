"""Level of detail of the manifold cloud: groups of one state and one grid cell, coloured from all their frames."""
import numpy as np
import pytest

from app.models.lod import cloud_detail


def _cloud(N=20000, K=40, seed=0):
    """Frames on a noisy curved sheet in 3-D, states as contiguous runs along it (like a state graph's)."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(0, 6, N)
    u = rng.normal(size=N)
    Y = np.column_stack([np.cos(t) * 3, np.sin(t) * 3, u]) + 0.05 * rng.normal(size=(N, 3))
    labels = np.minimum((t / 6 * K).astype(int), K - 1)
    return np.column_stack([Y, rng.normal(size=(N, 2))]), labels  # extra dims are ignored


def test_small_clouds_are_drawn_whole():
    Y, labels = _cloud(N=500)
    cd = cloud_detail(Y, labels, max_points=500)
    assert cd.whole and cd.n_points == 500 and cd.density is None and cd.cell is None
    np.testing.assert_array_equal(cd.frames, np.arange(500))
    np.testing.assert_array_equal(cd.state, labels)
    np.testing.assert_array_equal(cd.members([3, 7]), [3, 7])
    np.testing.assert_array_equal(cd.plurality(labels, 40), labels)


def test_groups_hold_one_state_and_one_cell_and_every_frame_once():
    Y, labels = _cloud()
    cap = 2000
    cd = cloud_detail(Y, labels, max_points=cap)
    N, G = len(labels), cd.n_points
    assert not cd.whole and 0.85 * cap <= G <= cap
    np.testing.assert_array_equal(np.sort(cd.order), np.arange(N))  # every frame in exactly one group
    assert cd.offsets[0] == 0 and cd.offsets[-1] == N and np.all(np.diff(cd.offsets) >= 1)
    np.testing.assert_array_equal(cd.group_of[cd.order], np.repeat(np.arange(G), cd.sizes))
    np.testing.assert_array_equal(labels, cd.state[cd.group_of])  # one state per group
    cell = np.floor((Y[:, :3] - cd.bounds[0]) / cd.cell).astype(int)
    for g in np.random.default_rng(1).choice(G, 50, replace=False):
        mem = cd.members(g)
        assert cd.frames[g] in mem and len(np.unique(cell[mem], axis=0)) == 1  # one grid cell
        far = np.linalg.norm(Y[mem, :3] - Y[cd.frames[g], :3], axis=1).max()
        assert far <= cd.radius[g] <= far * (1 + 1e-4) + 1e-5  # bounds the farthest member, tightly
        centre = Y[mem, :3].mean(axis=0)  # the drawn frame is the member nearest the members' mean
        d = np.linalg.norm(Y[mem, :3] - centre, axis=1)
        assert np.isclose(np.linalg.norm(Y[cd.frames[g], :3] - centre), d.min())
    np.testing.assert_array_equal(cloud_detail(Y, labels, max_points=cap).frames, cd.frames)  # deterministic


def test_density_counts_every_frame_of_the_cell():
    Y, labels = _cloud(N=8000)
    cd = cloud_detail(Y, labels, max_points=900)
    cell = [tuple(c) for c in np.floor((Y[:, :3] - cd.bounds[0]) / cd.cell).astype(int)]
    count = {}
    for c in cell:
        count[c] = count.get(c, 0) + 1
    want = np.log([count[cell[f]] / (len(Y) * cd.cell ** 3) for f in cd.frames])
    np.testing.assert_allclose(cd.density, want, rtol=1e-5)


def test_plurality_any_of_and_groups_of_follow_the_members():
    Y, labels = _cloud(N=6000)
    cd = cloud_detail(Y, labels, max_points=700)
    rng = np.random.default_rng(3)
    codes = rng.integers(0, 5, len(Y))
    for n_codes, c in ((5, codes), (3000, rng.integers(0, 3000, len(Y)))):  # dense table, then sort path
        got = cd.plurality(c, n_codes)
        for g in range(0, cd.n_points, 37):
            counts = np.bincount(c[cd.members(g)], minlength=n_codes)
            assert got[g] == int(np.argmax(counts))  # the most frequent, the smallest on a tie
    mask = np.zeros(len(Y), bool)
    mask[[5, 900, 4000]] = True
    np.testing.assert_array_equal(np.flatnonzero(cd.any_of(mask)), np.unique(cd.group_of[[5, 900, 4000]]))
    np.testing.assert_array_equal(cd.groups_of([5, 900, 900]), np.unique(cd.group_of[[5, 900]]))


def test_more_states_than_points_makes_a_group_of_each_state():
    Y, labels = _cloud(N=3000, K=300)
    cd = cloud_detail(Y, labels, max_points=200)
    assert cd.n_points == 300
    np.testing.assert_array_equal(np.sort(cd.state), np.arange(300))


def test_bad_input_is_named():
    Y, labels = _cloud(N=100)
    with pytest.raises(ValueError, match="max_points must be a positive integer"):
        cloud_detail(Y, labels, max_points=0)
    with pytest.raises(ValueError, match="labels must be a 1-D array of state indices"):
        cloud_detail(Y, labels.astype(float))
    with pytest.raises(ValueError, match="one row per label"):
        cloud_detail(Y[:50], labels)
    bad = Y.copy()
    bad[4, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        cloud_detail(bad, labels)


def test_scene_draws_the_groups_and_maps_points_back_to_frames():
    pv = pytest.importorskip("pyvista")
    from app.scene.manifold import add_manifold_points

    Y, labels = _cloud(N=3000)
    cd = cloud_detail(Y, labels, max_points=500)
    rng = np.random.default_rng(2)
    G = cd.n_points
    rgb = rng.integers(0, 256, (G, 3)).astype(np.uint8)
    values = rng.random(G).astype(np.float32)
    p = pv.Plotter(off_screen=True)
    try:
        h = add_manifold_points(p, Y, rgb, values, frames=cd.frames)
        assert h.mesh.n_points == G <= 500
        np.testing.assert_allclose(h.mesh.points, Y[cd.frames, :3], rtol=1e-6)
        np.testing.assert_array_equal(h.rgb, rgb)  # one colour per drawn point is kept as given
        np.testing.assert_array_equal(h.values, values)
        assert [h.frame_of(i) for i in (0, 7, G - 1)] == [cd.frames[0], cd.frames[7], cd.frames[-1]]
        per_frame = rng.integers(0, 256, (len(Y), 3)).astype(np.uint8)
        h.set_colors(per_frame)  # one colour per frame: the drawn frames' are kept
        np.testing.assert_array_equal(h.rgb, per_frame[cd.frames])
        whole = add_manifold_points(p, Y, name="all")
        assert whole.mesh.n_points == len(Y) and whole.frame_of(5) == 5
    finally:
        p.close()

"""Level of detail of the manifold cloud: every state drawn, frames capped, proportions kept (issue 13 item 8)."""
import numpy as np
import pytest

from app.lod import cloud_subsample


def test_small_clouds_are_drawn_whole():
    np.testing.assert_array_equal(cloud_subsample(np.array([2, 0, 1, 1]), max_frames=4), np.arange(4))


def test_large_cloud_keeps_every_state_and_its_share():
    rng = np.random.default_rng(0)
    sizes = np.r_[1, 3, rng.integers(50, 5000, size=298)]  # two tiny states among large ones
    labels = rng.permutation(np.repeat(np.arange(300), sizes))
    cap = 20_000
    idx = cloud_subsample(labels, max_frames=cap)
    assert np.all(np.diff(idx) > 0) and idx[0] >= 0 and idx[-1] < len(labels)
    assert cap * 0.9 <= len(idx) <= cap + 300
    drawn = np.bincount(labels[idx], minlength=300)
    assert drawn.min() >= 1  # the 1-frame and 3-frame states are drawn
    big = sizes >= 1000
    np.testing.assert_allclose(drawn[big] / len(idx), sizes[big] / sizes.sum(), rtol=0.05)
    np.testing.assert_array_equal(cloud_subsample(labels, max_frames=cap), idx)  # deterministic
    assert not np.array_equal(cloud_subsample(labels, max_frames=cap, random_state=1), idx)


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="max_frames must be a positive integer"):
        cloud_subsample(np.zeros(3, int), max_frames=0)
    with pytest.raises(ValueError, match="labels must be a 1-D array of state indices"):
        cloud_subsample(np.array([0.5, 1.0]))


def test_scene_draws_the_subsample_and_maps_points_back_to_frames():
    pv = pytest.importorskip("pyvista")
    from app.lod import cloud_frames
    from app.scene.manifold import add_manifold_points

    rng = np.random.default_rng(2)
    N = 3000
    Y = rng.standard_normal((N, 3))
    labels = rng.integers(0, 40, N)
    assert cloud_frames(labels, max_frames=N) is None  # small: every frame drawn, point i is frame i
    idx = cloud_frames(labels, max_frames=500)
    rgb = rng.integers(0, 256, (N, 3)).astype(np.uint8)
    values = rng.random(N).astype(np.float32)
    p = pv.Plotter(off_screen=True)
    try:
        h = add_manifold_points(p, Y, rgb, values, frames=idx)
        assert h.mesh.n_points == len(idx) < 600
        np.testing.assert_allclose(h.mesh.points, Y[idx], rtol=1e-6)
        np.testing.assert_array_equal(h.rgb, rgb[idx])  # one colour per frame in, the drawn frames' out
        np.testing.assert_array_equal(h.values, values[idx])
        assert [h.frame_of(i) for i in (0, 7, len(idx) - 1)] == [idx[0], idx[7], idx[-1]]
        h.set_colors(rgb[::-1], values[::-1])
        np.testing.assert_array_equal(h.rgb, rgb[::-1][idx])
        drawn = add_manifold_points(p, Y, rgb[idx], values[idx], frames=idx, name="drawn")
        np.testing.assert_array_equal(drawn.rgb, rgb[idx])  # one colour per drawn point is kept as given
        np.testing.assert_array_equal(drawn.values, values[idx])
        whole = add_manifold_points(p, Y, name="all")
        assert whole.mesh.n_points == N and whole.frame_of(5) == 5
    finally:
        p.close()

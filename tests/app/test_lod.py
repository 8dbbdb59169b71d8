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

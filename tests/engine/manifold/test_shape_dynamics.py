import numpy as np
import pytest

from engine.manifold.dynamics import DynamicFeatures
from engine.manifold.shape import ShapeSpace
from engine.recordings.bounds import velocities


@pytest.fixture(scope="module")
def lowrank():
    rng = np.random.default_rng(1)
    lat = rng.standard_normal((500, 6)) * [6, 3, 2, 1, 0.5, 0.2]
    F = lat @ rng.standard_normal((6, 120)) + 0.01 * rng.standard_normal((500, 120)) + 5.0
    return F.astype(np.float32)


def test_shape_matches_dense_pca(lowrank):
    s = ShapeSpace(max_components=20, variance=0.999).fit(lowrank)
    Fc = lowrank.astype(np.float64) - lowrank.mean(0)
    _, S, Vt = np.linalg.svd(Fc, full_matrices=False)
    ratio = S**2 / (S**2).sum()
    np.testing.assert_allclose(s.scree_[:6], ratio[:6], rtol=1e-3)
    cos = np.abs(np.sum(s.components_[:5] * Vt[:5], axis=1))
    assert cos.min() > 0.999
    assert s.n_components_ == int(np.searchsorted(np.cumsum(S[:20] ** 2) / (S[:20] ** 2).sum(), 0.999) + 1)
    # the reconstruction error is exactly the variance the dropped components held
    R = s.inverse_transform(s.transform(lowrank)).astype(np.float64)
    residual = ((R - lowrank) ** 2).sum(1).mean()
    dropped = (S[s.n_components_:] ** 2).sum() / (len(lowrank) - 1)
    np.testing.assert_allclose(residual * len(lowrank) / (len(lowrank) - 1), dropped, rtol=2e-2)
    # keeping every informative component reconstructs to the noise level
    full = ShapeSpace(max_components=20, variance=1.0).fit(lowrank)
    assert np.abs(full.inverse_transform(full.transform(lowrank)) - lowrank).max() < 0.1


def test_variance_threshold_picks_smallest_m(lowrank):
    s = ShapeSpace(max_components=20, variance=0.9).fit(lowrank)
    cum = s.recovered_ratio_
    m = s.n_components_
    assert cum[m - 1] >= 0.9 - 1e-9 and (m == 1 or cum[m - 2] < 0.9)


def test_shape_rejects_bad_input():
    with pytest.raises(ValueError, match="variance must be in"):
        ShapeSpace(variance=1.5).fit(np.ones((10, 3)))
    F = np.random.default_rng(0).standard_normal((10, 6))
    F[4, 2] = np.nan
    with pytest.raises(ValueError, match="frame 4"):
        ShapeSpace().fit(F)


def test_component1_is_jaw_opening(small_corpus, small_manifold):
    jaw = small_corpus.latent["jaw"]
    r = np.corrcoef(small_manifold.Fx_[:, 0], jaw)[0, 1]
    print(f"corr(X component 1, true jaw opening) = {r:.3f}")
    assert r > 0.9  # oriented: positive = opening


def test_velocities_never_cross_utterances():
    Fx = np.arange(10, dtype=np.float32)[:, None] ** 2
    b = np.array([[0, 4], [4, 10]])
    V = velocities(Fx, b)
    assert V[:, 0].tolist() == [1, 1, 3, 5, 9, 9, 11, 13, 15, 17]
    with pytest.raises(ValueError, match="contiguous"):
        velocities(Fx, np.array([[0, 4], [5, 10]]))


def test_g_blocks_in_unit_range(small_manifold):
    G = small_manifold.G_
    m = small_manifold.Fx_.shape[1]
    for block in (G[:, :m], G[:, m:]):
        assert np.abs(block).max() == pytest.approx(1.0, abs=1e-6)
        np.testing.assert_allclose(block.mean(0), 0, atol=1e-4)
    d = small_manifold.dynamics_
    assert isinstance(d.alpha_, float) and isinstance(d.beta_, float)  # one scalar per block


def test_dynamics_rejects_still_lips():
    with pytest.raises(ValueError, match="the lip shape never changes"):
        DynamicFeatures().fit(np.ones((5, 2)), np.array([[0, 5]]))
    Fx = np.arange(10.0).reshape(5, 2)  # shapes that change, but one frame per utterance: no velocity at all
    with pytest.raises(ValueError, match="every utterance holds a single frame .5 utterances.: a velocity needs"):
        DynamicFeatures().fit(Fx, np.array([[k, k + 1] for k in range(5)]))

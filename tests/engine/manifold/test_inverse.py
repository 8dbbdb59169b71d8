import numpy as np
import pytest

from engine.files.persist import dump_estimator, load_estimator
from engine.manifold.inverse import InverseMap


def _cloud(n=400, m=6, seed=0):
    rng = np.random.default_rng(seed)
    Y = rng.standard_normal((n, 5)).astype(np.float32)
    X = rng.standard_normal((n, m)).astype(np.float32)
    return Y, X


def test_training_points_map_to_their_own_values():
    Y, X = _cloud()
    im = InverseMap().fit(Y, X)
    np.testing.assert_array_equal(im.transform(Y), X)
    assert im.transform(Y).dtype == np.float32


def test_duplicates_and_near_coincident_points_still_reproduce():
    Y, X = _cloud(300)
    Y[10] = Y[3]
    X[10] = X[3]  # exact duplicate frame
    Y[20] = Y[4] + np.float32(1e-7)  # near-coincident: Qhull may leave it out of the triangulation
    Y[21] = Y[4] * 1.0000001
    im = InverseMap().fit(Y, X)
    assert im.n_duplicates_ == 1 and im.duplicate_spread_ == 0.0
    np.testing.assert_allclose(im.transform(Y), X, rtol=0, atol=1e-6)


def test_duplicates_with_different_values_report_spread():
    Y, X = _cloud(100)
    Y[1] = Y[0]
    X[1] = X[0] + 2.0
    im = InverseMap().fit(Y, X)
    np.testing.assert_allclose(im.transform(Y[:1])[0], X[0] + 1.0, atol=1e-6)
    assert im.duplicate_spread_ == pytest.approx(np.sqrt(X.shape[1]), rel=1e-6)


def test_inside_points_are_barycentric_combinations_of_a_simplex():
    Y, X = _cloud(200, m=3, seed=1)
    im = InverseMap().fit(Y, X)
    rng = np.random.default_rng(2)
    # a point inside a known simplex: a convex combination of its vertices
    s = im.simplices_[rng.integers(len(im.simplices_))]
    w = rng.dirichlet(np.ones(4))
    P = im.points_[s]  # subspace coordinates (identity basis, centred)
    q = w @ P + im.origin_
    out, outside = im.transform(q[None, :], return_outside=True)
    np.testing.assert_allclose(out[0], w @ im.values_[s].astype(np.float64), rtol=1e-5, atol=1e-5)
    assert not outside[0]


def test_linear_function_is_reproduced_exactly_inside_the_hull():
    rng = np.random.default_rng(3)
    Y = rng.uniform(-1, 1, (300, 3))
    A = rng.standard_normal((3, 4))
    im = InverseMap().fit(Y, Y @ A)
    q = rng.uniform(-0.5, 0.5, (50, 3))
    out, outside = im.transform(q, return_outside=True)
    assert not outside.any()
    np.testing.assert_allclose(out, q @ A, atol=1e-9)


def test_outside_points_use_clamped_weights_of_a_nearby_simplex():
    rng = np.random.default_rng(4)
    Y = rng.uniform(-1, 1, (200, 3))
    X = Y @ rng.standard_normal((3, 2)) + 5.0
    im = InverseMap().fit(Y, X)
    q = np.array([[3.0, 0.0, 0.0], [0.0, -4.0, 0.5], [10.0, 10.0, 10.0]])
    out, outside = im.transform(q, return_outside=True)
    assert outside.all()
    assert np.isfinite(out).all()
    # convex combinations of fitted values: inside their bounding box, never zeros
    assert (out >= X.min(axis=0) - 1e-9).all() and (out <= X.max(axis=0) + 1e-9).all()
    assert not np.any(np.all(out == 0, axis=1))


def test_degenerate_planar_and_linear_inputs():
    rng = np.random.default_rng(5)
    plane = np.c_[rng.standard_normal((60, 2)), np.zeros(60)]
    X = rng.standard_normal((60, 3))
    im = InverseMap().fit(plane, X)
    assert im.rank_ == 2
    np.testing.assert_allclose(im.transform(plane), X, atol=1e-12)
    _, off = im.transform(np.array([[0.0, 0.0, 1.0]]), return_outside=True)
    assert off[0]
    line = np.c_[np.linspace(0, 1, 11), np.zeros(11), np.zeros(11)]
    im1 = InverseMap().fit(line, X[:11])
    assert im1.rank_ == 1
    np.testing.assert_allclose(im1.transform([[0.05, 0, 0]])[0], 0.5 * (X[0] + X[1]), atol=1e-12)


def test_fitted_state_saves_as_arrays_and_reloads(tmp_path):
    Y, X = _cloud(150)
    im = InverseMap().fit(Y, X)
    d = dump_estimator(im, "inv")
    np.savez(tmp_path / "inv.npz", **d)
    with np.load(tmp_path / "inv.npz", allow_pickle=False) as z:
        back = load_estimator(InverseMap, {k: z[k] for k in z.files}, "inv")
    q = np.random.default_rng(6).standard_normal((40, 3))
    np.testing.assert_array_equal(back.transform(q), im.transform(q))
    np.testing.assert_array_equal(back.simplices_, im.simplices_)


def test_bad_input_messages():
    Y, X = _cloud(20)
    with pytest.raises(ValueError, match="rows like Fy"):
        InverseMap().fit(Y, X[:10])
    with pytest.raises(ValueError, match="at least n_dims=3"):
        InverseMap().fit(Y[:, :2], X)
    bad = Y.copy()
    bad[4, 1] = np.nan
    with pytest.raises(ValueError, match="row 4"):
        InverseMap().fit(bad, X)
    im = InverseMap().fit(Y, X)
    with pytest.raises(ValueError, match="at least n_dims"):
        im.transform(np.zeros((2, 2)))


def test_manifold_inverse_map_reproduces_training_frames(small_manifold):
    m = small_manifold
    im = InverseMap().fit(m.Fy_, m.Fx_)
    idx = np.arange(0, m.Fy_.shape[0], 7)
    np.testing.assert_allclose(im.transform(m.Fy_[idx]), m.Fx_[idx], rtol=0, atol=1e-5 * np.abs(m.Fx_).max())
    frames = m.shape_.inverse_transform(im.transform(m.Fy_[idx]))
    np.testing.assert_allclose(frames, m.shape_.inverse_transform(m.Fx_[idx]), atol=1e-4 * np.abs(frames).max())


@pytest.mark.parametrize("r", [2, 3, 4])
def test_batch_barycentric_transforms_match_scipy(r):
    """The batch transforms equal scipy's per-simplex ones, NaN where scipy says degenerate."""
    from scipy.spatial import Delaunay

    from engine.manifold.inverse import barycentric_transforms

    rng = np.random.default_rng(r)
    P = rng.standard_normal((1500, r))
    # a regular grid block makes cospherical / flat simplices Qhull keeps with "Qz Q12"
    g = np.stack(np.meshgrid(*[np.arange(4.0)] * r, indexing="ij"), -1).reshape(-1, r)
    P = np.vstack([P, g * 0.3 + 3.0])
    tri = Delaunay(P, qhull_options="Qbb Qc Qz Q12")
    ref = tri.transform
    T = barycentric_transforms(tri.points, tri.simplices)
    assert T.shape == ref.shape
    ok = np.isfinite(ref).all(axis=(1, 2))
    # the same simplices are degenerate (scipy estimates the condition number, we compute it)
    assert np.array_equal(ok, np.isfinite(T).all(axis=(1, 2)))
    np.testing.assert_allclose(T[ok], ref[ok], rtol=1e-9, atol=1e-9 * np.abs(ref[ok]).max())


def test_flat_simplex_transform_is_nan():
    from engine.manifold.inverse import barycentric_transforms

    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1.0]])
    T = barycentric_transforms(pts, np.array([[0, 1, 2, 3], [0, 1, 2, 4]]))
    assert np.isnan(T[0]).all() and np.isfinite(T[1]).all()
    c = T[1, :3] @ (np.array([0.2, 0.2, 0.2]) - T[1, 3])
    np.testing.assert_allclose(np.r_[c, 1 - c.sum()], [0.4, 0.2, 0.2, 0.2], atol=1e-12)


def test_triangulation_uses_batch_transforms():
    Y, X = _cloud(500)
    im = InverseMap().fit(Y, X)
    tri = im._triangulation()
    assert tri._transform is not None  # handed over before scipy's lazy per-simplex path
    from engine.manifold.inverse import barycentric_transforms

    np.testing.assert_array_equal(tri.transform, barycentric_transforms(tri.points, tri.simplices))

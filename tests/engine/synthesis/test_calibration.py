"""State velocities calibrated on the targets by leave one target out (engine.synthesis.calibration)."""

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator

from engine.synthesis.calibration import calibrated_spline, calibration_weight, pchip_slopes
from engine.synthesis.trajectory import interpolate_targets


def _targets(rng, T, m=3):
    f = np.cumsum(rng.integers(2, 14, T)).astype(float)
    X = rng.normal(size=(T, m))
    X[:, -1] = np.round(X[:, -1])  # flat secants and sign changes: PCHIP's special cases
    return f, X


def test_pchip_slopes_are_scipys_at_the_knots():
    rng = np.random.default_rng(0)
    for T in (3, 4, 5, 9, 40):
        for _ in range(10):
            f, X = _targets(rng, T)
            np.testing.assert_allclose(pchip_slopes(f, X), PchipInterpolator(f, X, axis=0).derivative()(f),
                                       atol=1e-12)
    f, X = _targets(rng, 2)
    np.testing.assert_allclose(pchip_slopes(f, X), np.repeat((X[1:] - X[:1]) / (f[1] - f[0]), 2, axis=0))
    np.testing.assert_array_equal(pchip_slopes([4.0], [[1.0, 2.0]]), [[0.0, 0.0]])


def _left_out_error(f, X, V, w):
    """Squared error at every inner target of the Hermite spline through the others (scipy, one by one)."""
    err = 0.0
    for i in range(1, len(f) - 1):
        keep = np.r_[0:i, i + 1:len(f)]
        fk, Xk = f[keep], X[keep]
        D = PchipInterpolator(fk, Xk, axis=0).derivative()(fk) if keep.size > 2 else \
            np.repeat((Xk[1:] - Xk[:1]) / (fk[1] - fk[0]), 2, axis=0)
        U = D + w * (V[keep] - D)
        err += float(((CubicHermiteSpline(fk, Xk, U, axis=0)(f[i]) - X[i]) ** 2).sum())
    return err


def test_the_weight_minimises_the_left_out_targets_error():
    """The closed form against a grid search over w of the error that scipy's splines make, target by target."""
    rng = np.random.default_rng(1)
    grid = np.linspace(0, 1, 201)
    for T in (3, 4, 6, 25):
        for _ in range(4):
            f, X = _targets(rng, T)
            V = rng.normal(size=X.shape) * 0.3
            w = calibration_weight(f, X, V)
            errs = np.array([_left_out_error(f, X, V, g) for g in grid])
            assert 0.0 <= w <= 1.0
            assert _left_out_error(f, X, V, w) <= errs.min() + 1e-9, (T, w, grid[errs.argmin()])


def test_true_velocities_are_kept_and_misleading_ones_dropped():
    """Targets on a smooth movement: its own derivatives earn w near 1, reversed ones w = 0, and the
    calibrated spline then follows the movement between the targets better than the state velocities."""
    t = np.arange(0, 240, dtype=float)
    x = np.column_stack([np.sin(t / 9.0), np.cos(t / 13.0) * 2])
    v = np.column_stack([np.cos(t / 9.0) / 9.0, -np.sin(t / 13.0) * 2 / 13.0])
    f = np.arange(0, 240, 11)
    assert calibration_weight(f, x[f], v[f]) > 0.9
    assert calibration_weight(f, x[f], -v[f]) == 0.0
    lo, hi = f[0], f[-1]
    calibrated = calibrated_spline(f, x[f], -v[f], 240)
    np.testing.assert_array_equal(calibrated, interpolate_targets("pchip", f, x[f], 240))  # w = 0: PCHIP itself
    misled = CubicHermiteSpline(f, x[f], -v[f], axis=0)(t[lo:hi])
    assert np.abs(calibrated[lo:hi] - x[lo:hi]).mean() < 0.3 * np.abs(misled - x[lo:hi]).mean()


def test_too_few_targets_or_nothing_to_choose_keep_the_state_velocities():
    X = np.array([[0.0], [1.0]])
    assert calibration_weight([0, 5], X, [[0.3], [0.1]]) == 1.0
    f = np.array([0.0, 4.0, 9.0, 15.0])
    X = np.array([[0.0], [1.0], [0.5], [2.0]])
    assert calibration_weight(f, X, pchip_slopes(f, X)) == 1.0  # V equals the slopes: w is moot
    np.testing.assert_array_equal(calibrated_spline(f, X, pchip_slopes(f, X), 20),
                                  interpolate_targets("hermite", f, X, 20, pchip_slopes(f, X)))  # w = 1: the spline
    V = pchip_slopes(f, X) + np.array([[0.2], [0.6], [-0.4], [0.2]])
    w = calibration_weight(f, X, V)
    assert 0 < w < 1
    D = pchip_slopes(f, X)
    np.testing.assert_allclose(calibrated_spline(f, X, V, 20),
                               interpolate_targets("hermite", f, X, 20, D + w * (V - D)))


@pytest.mark.parametrize("T", [1, 2, 3, 7])
def test_the_calibrated_base_passes_through_the_targets(small_manifold, T):
    """The calibrated base goes through the given X; through the states' own means it is the state-velocity
    Hermite spline (nothing observed to calibrate against)."""
    from engine.synthesis.learnt_paths import BASES
    from engine.synthesis.statepaths import StateModel

    m = small_manifold
    c = m.corpus_
    sm = StateModel(state_dims=3).fit(m.Fy_, m.Fx_, m.Fxv_, c.bounds)
    u = c.utterances[0]
    f = np.linspace(3, u.n_frames - 4, T).round().astype(int)
    st = sm.predict(np.asarray(m.Fy_[u.start:u.stop])[f])
    xt = np.asarray(m.Fx_[u.start:u.stop], np.float64)[f]
    cal = BASES.index("calibrated")
    B = sm.bases_x(f, st, u.n_frames, xt)
    np.testing.assert_allclose(B[cal][f], xt, atol=1e-9)
    S = sm.bases_x(f, st, u.n_frames)
    np.testing.assert_allclose(S[cal], S[BASES.index("hermite")])

"""State velocities calibrated against the targets' own X by leave one target out.

The state-velocity Hermite spline takes each target's velocity from its state's mean
F^x'. Those means are the training speech's: where the talker being synthesised moves
otherwise (another speaker, little training speech, states that mix movements), they
mislead, and the slopes the targets themselves imply -- PCHIP's (Fritsch--Carlson) --
are the better guess. Which to trust is measured on the targets, never on the frames
between them: each inner target ``i`` is left out in turn and predicted from the cubic
Hermite segment between targets ``i - 1`` and ``i + 1`` whose end velocities are

    U = D + w (V - D)

(``V`` the states' mean velocities, ``D`` the PCHIP slopes of the targets without
``i``). The prediction error is linear in ``w``, so the ``w`` in [0, 1] with the least
squared error over every left-out target and shape component has a closed form
(:func:`calibration_weight`). :func:`calibrated_spline` is the Hermite spline through
the targets with ``U`` made from the PCHIP slopes of all of them. Everything is
vectorised over targets and components: one synthesis costs a few array operations more
than the spline.

Calibration needs targets whose X was observed (the ``oracle`` protocol: an utterance's
own frames at its targets); through the states' own means there is nothing to calibrate
against and the state velocities stand (``w = 1``).
"""
from __future__ import annotations

import numpy as np

__all__ = ["pchip_slopes", "calibration_weight", "calibrated_spline"]


def _secants(f0, x0, f1, x1):
    h = (f1 - f0)[:, None]
    return h, (x1 - x0) / h


def _inner_slope(h0, m0, h1, m1):
    """PCHIP's slope at a knot between an interval (h0, secant m0) and the next (h1, m1): a weighted
    harmonic mean of the secants, 0 where they differ in sign or either is 0."""
    w1, w2 = 2 * h1 + h0, h1 + 2 * h0
    with np.errstate(divide="ignore", invalid="ignore"):
        d = (w1 + w2) / (w1 / m0 + w2 / m1)
    flat = (np.sign(m0) != np.sign(m1)) | (m0 == 0) | (m1 == 0)
    return np.where(flat, 0.0, d)


def _end_slope(h0, m0, h1, m1):
    """PCHIP's slope at an end knot: the three-point estimate, kept shape-preserving."""
    d = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    d = np.where(np.sign(d) != np.sign(m0), 0.0, d)
    return np.where((np.sign(m0) != np.sign(m1)) & (np.abs(d) > 3 * np.abs(m0)), 3 * m0, d)


def pchip_slopes(frames, X) -> np.ndarray:
    """The slopes (T, m) of :class:`scipy.interpolate.PchipInterpolator` at its knots ``frames`` (T,).

    Two targets: the secant at both; one: zeros.
    """
    f = np.asarray(frames, dtype=np.float64)
    X = np.asarray(X, dtype=np.float64)
    if f.size < 2:
        return np.zeros_like(X)
    h, m = _secants(f[:-1], X[:-1], f[1:], X[1:])
    if f.size == 2:
        return np.repeat(m, 2, axis=0)
    d = np.empty_like(X)
    d[1:-1] = _inner_slope(h[:-1], m[:-1], h[1:], m[1:])
    d[0] = _end_slope(h[0], m[0], h[1], m[1])
    d[-1] = _end_slope(h[-1], m[-1], h[-2], m[-2])
    return d


def _left_out_slopes(f, X):
    """PCHIP slopes at targets i - 1 and i + 1 of the targets without i, for every inner i: (T - 2, m) each."""
    T = f.size
    i = np.arange(1, T - 1)
    hc, mc = _secants(f[i - 1], X[i - 1], f[i + 1], X[i + 1])  # the interval that replaces target i
    if T == 3:  # two targets left: PCHIP is their secant
        return mc, mc
    a, b = np.empty_like(mc), np.empty_like(mc)
    lo, hi = i >= 2, i <= T - 3  # target i - 1 has a left neighbour; target i + 1 a right one
    il, ir = i[lo], i[hi]
    hl, ml = _secants(f[il - 2], X[il - 2], f[il - 1], X[il - 1])
    a[lo] = _inner_slope(hl, ml, hc[lo], mc[lo])
    hr, mr = _secants(f[ir + 1], X[ir + 1], f[ir + 2], X[ir + 2])
    b[hi] = _inner_slope(hc[hi], mc[hi], hr, mr)
    ie = i[~lo]  # i == 1: target 0 is the first knot, the next interval runs from target 2 to 3
    hn, mn = _secants(f[ie + 1], X[ie + 1], f[ie + 2], X[ie + 2])
    a[~lo] = _end_slope(hc[~lo], mc[~lo], hn, mn)
    ie = i[~hi]  # i == T - 2: target T - 1 is the last knot, the interval before runs from T - 4 to T - 3
    hp, mp = _secants(f[ie - 2], X[ie - 2], f[ie - 1], X[ie - 1])
    b[~hi] = _end_slope(hc[~hi], mc[~hi], hp, mp)
    return a, b


def calibration_weight(frames, X, V) -> float:
    """The share ``w`` in [0, 1] of the state velocities that predicts left-out targets best.

    Parameters
    ----------
    frames : ndarray of shape (T,)
        Increasing target frames.
    X : ndarray of shape (T, m)
        The targets' observed X.
    V : ndarray of shape (T, m)
        The target states' mean velocities (X per frame).

    Returns
    -------
    float
        The least-squares ``w`` (see the module docstring), clipped to [0, 1]; 1 with fewer
        than three targets or where ``V`` equals the slopes (nothing to choose).
    """
    f = np.asarray(frames, dtype=np.float64)
    X = np.asarray(X, dtype=np.float64)
    V = np.asarray(V, dtype=np.float64)
    if f.size < 3:
        return 1.0
    i = np.arange(1, f.size - 1)
    Da, Db = _left_out_slopes(f, X)
    h = (f[i + 1] - f[i - 1])[:, None]
    t = ((f[i] - f[i - 1]) / (f[i + 1] - f[i - 1]))[:, None]
    h00, h10, h01, h11 = 2 * t ** 3 - 3 * t ** 2 + 1, t ** 3 - 2 * t ** 2 + t, 3 * t ** 2 - 2 * t ** 3, t ** 3 - t ** 2
    a = h00 * X[i - 1] + h10 * h * Da + h01 * X[i + 1] + h11 * h * Db - X[i]  # error with the slopes alone
    b = h10 * h * (V[i - 1] - Da) + h11 * h * (V[i + 1] - Db)  # what w moves it by
    bb = float((b * b).sum())
    if not bb > 0:
        return 1.0
    return float(np.clip(-float((a * b).sum()) / bb, 0.0, 1.0))


def calibrated_spline(frames, X, V, n_frames) -> np.ndarray:
    """The cubic Hermite spline (n_frames, m) through the targets with the velocities ``D + w (V - D)``.

    ``D`` are PCHIP's slopes through the targets and ``w`` is :func:`calibration_weight`: at
    ``w = 0`` the trajectory is PCHIP's, at ``w = 1`` the state-velocity Hermite spline's,
    each made by that interpolation itself (so an equality with either baseline is exact).
    """
    from engine.synthesis.trajectory import interpolate_targets

    w = calibration_weight(frames, X, V)
    if w == 0.0:
        return interpolate_targets("pchip", frames, X, n_frames)
    V = np.asarray(V, dtype=np.float64)
    if w < 1.0:
        D = pchip_slopes(frames, X)
        V = D + w * (V - D)
    return interpolate_targets("hermite", frames, X, n_frames, V)

"""Inverse maps Y -> X in any number of dimensions: state means and local-linear regression.

The paper's inverse (:class:`engine.manifold.inverse.InverseMap`) tetrahedralises the first 3
dims of F^y. Three dimensions of Y do not carry all of X: on the synthetic talker Y1-3
explain F^x_1 and its velocity but hardly the lip rounding F^x_2, which Y4-5 carry.
A Delaunay triangulation above 3-D is impractical (minutes to build at 26k points in
5-D), so two maps that scale to any dimension stand beside it:

:class:`StateMeanInverse`
    X of a state = the mean F^x of the training frames in that state. The natural
    inverse of a state path (the path *is* a sequence of states).
:class:`LocalLinearInverse`
    For a query point y, the k nearest training frames in the first ``n_dims`` of F^y
    and a ridge-regularised least-squares affine fit ``x ~ a + B (y_j - y)`` over
    them; the answer is the intercept ``a``. Exact for data that are locally affine in
    Y, and a k-NN mean when the neighbours are degenerate. ``k`` is chosen on
    validation data with :func:`select_neighbors`.
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np
from scipy.spatial import cKDTree

from engine.constraints import Interval, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.threads import single_blas_thread

__all__ = ["StateMeanInverse", "LocalLinearInverse", "select_neighbors", "NEIGHBOR_CANDIDATES"]

#: k tried by :func:`select_neighbors`
NEIGHBOR_CANDIDATES = (10, 20, 40, 80, 160)
#: queries solved per batch (memory: batch * k * (d + 1) floats)
_BATCH = 4096


def _check_2d(A, name, cols=None) -> np.ndarray:
    A = np.asarray(A, dtype=np.float64)
    if A.ndim != 2:
        raise ValueError(f"{name} must be a 2-D (n, dims) array, got shape {A.shape}")
    if cols is not None and A.shape[1] < cols:
        raise ValueError(f"{name} needs at least {cols} columns (n_dims), got shape {A.shape}; "
                         f"lower n_dims or pass more dimensions of F^y")
    bad = ~np.isfinite(A).all(axis=1)
    if bad.any():
        raise ValueError(f"{name} holds NaN or infinite values (first at row {int(np.flatnonzero(bad)[0])})")
    return A


class StateMeanInverse(Estimator):
    """X of each state: the mean F^x (and mean velocity F^x') of its training frames.

    Use ``fit(labels, Fx, Fxv)`` then ``transform(states)``.

    Attributes
    ----------
    means_ : ndarray of shape (K, m)
        Mean F^x per state.
    velocity_means_ : ndarray of shape (K, m) or None
        Mean F^x' per state (None when ``Fxv`` was not given).
    counts_ : ndarray of shape (K,), int
        Training frames per state (0 for a state without frames: its mean is the
        overall mean).
    """

    _parameter_constraints: dict = {}  # no parameters

    def fit(self, labels, Fx, Fxv=None, *, n_states=None):
        """Average ``Fx`` (N, m) and ``Fxv`` (N, m) over the state ``labels`` (N,) in 0..K-1."""
        lab = np.asarray(labels, dtype=np.int64).reshape(-1)
        Fx = _check_2d(Fx, "F^x")
        if lab.size != Fx.shape[0]:
            raise ValueError(f"labels has {lab.size} entries but F^x has {Fx.shape[0]} rows; give one state per frame")
        if lab.size and lab.min() < 0:
            raise ValueError(f"state labels must be >= 0, got {int(lab.min())}")
        K = int(n_states) if n_states is not None else int(lab.max()) + 1
        n = np.bincount(lab, minlength=K)
        if n.size > K:
            raise ValueError(f"labels go up to {n.size - 1} but n_states={K}")

        def avg(A):
            s = np.stack([np.bincount(lab, weights=A[:, j], minlength=K) for j in range(A.shape[1])], 1)
            return np.where(n[:, None] > 0, s / np.maximum(n, 1)[:, None], A.mean(axis=0))

        self.means_ = avg(Fx)
        self.velocity_means_ = None if Fxv is None else avg(_check_2d(Fxv, "F^x'"))
        self.counts_ = n
        return self

    def transform(self, states) -> np.ndarray:
        """Mean F^x of each state: ndarray (n,) int -> (n, m) float64."""
        check_is_fitted(self, "means_")
        s = np.asarray(states, dtype=np.int64).reshape(-1)
        K = self.means_.shape[0]
        if s.size and (s.min() < 0 or s.max() >= K):
            raise ValueError(f"state indices must be in 0..{K - 1}, got {int(s.min())}..{int(s.max())}")
        return self.means_[s]


class LocalLinearInverse(Estimator):
    """Local-linear regression of F^x on the first ``n_dims`` of F^y over the k nearest frames.

    Parameters
    ----------
    n_neighbors : int, default=40
        k, training frames per local fit (at least ``n_dims + 2``).
    n_dims : int, default=5
        Leading coordinates of F^y used.
    ridge : float, default=1e-3
        Ridge on the slope, relative to the mean squared neighbour offset (keeps the
        fit stable where the neighbours are nearly degenerate; the intercept is never
        penalised).

    Attributes
    ----------
    points_ : ndarray of shape (N, n_dims)
    values_ : ndarray of shape (N, m)
    """

    _parameter_constraints = {
        "n_neighbors": [Interval(Integral, 3, None, closed="left")],  # n_dims + 2 at least, checked by fit
        "n_dims": [Interval(Integral, 1, None, closed="left")],
        "ridge": [Interval(Real, 0, None, closed="left")],
    }

    def __init__(self, *, n_neighbors=40, n_dims=5, ridge=1e-3):
        self.n_neighbors = n_neighbors
        self.n_dims = n_dims
        self.ridge = ridge

    def fit(self, Fy, Fx):
        """Store the training pairs: F^y (N, >= n_dims) and F^x (N, m)."""
        validate_params(self)
        d, k = int(self.n_dims), int(self.n_neighbors)
        Fy = _check_2d(Fy, "F^y", d)[:, :d]
        Fx = _check_2d(Fx, "F^x")
        if Fy.shape[0] != Fx.shape[0]:
            raise ValueError(f"F^y has {Fy.shape[0]} rows but F^x has {Fx.shape[0]}; give one F^x per frame")
        if not d + 2 <= k <= Fy.shape[0]:
            raise ValueError(f"n_neighbors must be in {d + 2}..{Fy.shape[0]} (n_dims + 2 .. training frames), "
                             f"got {self.n_neighbors}; choose k in that range")
        self.points_, self.values_ = Fy, Fx
        self._tree = None  # built by the first transform: a synthesis that never maps through it does not pay it
        return self

    @single_blas_thread
    def transform(self, Y) -> np.ndarray:
        """F^x at query points: ndarray (n, >= n_dims) -> (n, m) float64."""
        check_is_fitted(self, "points_")
        d, k = int(self.n_dims), int(self.n_neighbors)
        Y = _check_2d(np.atleast_2d(Y), "Y", d)[:, :d]
        if getattr(self, "_tree", None) is None:
            self._tree = cKDTree(self.points_)
        out = np.empty((Y.shape[0], self.values_.shape[1]))
        eye = np.eye(d + 1)
        eye[0, 0] = 0.0  # no ridge on the intercept
        for s in range(0, Y.shape[0], _BATCH):
            q = Y[s:s + _BATCH]
            idx = self._tree.query(q, k=k, workers=-1)[1]
            D = self.points_[idx] - q[:, None, :]                      # (b, k, d)
            A = np.concatenate([np.ones(D.shape[:2] + (1,)), D], axis=2)  # (b, k, d+1)
            AtA = np.einsum("bki,bkj->bij", A, A)
            scale = np.einsum("bkd,bkd->b", D, D) / k
            AtA += float(self.ridge) * np.maximum(scale, 1e-12)[:, None, None] * eye
            Atv = np.einsum("bki,bkm->bim", A, self.values_[idx])
            out[s:s + _BATCH] = np.linalg.solve(AtA, Atv)[:, 0, :]
        return out


def select_neighbors(Fy_fit, Fx_fit, Fy_val, Fx_val, *, n_dims, candidates=NEIGHBOR_CANDIDATES) -> tuple[int, dict]:
    """k of :class:`LocalLinearInverse` with the smallest RMS error on validation frames.

    Parameters
    ----------
    Fy_fit, Fx_fit : ndarray of shape (N, >= n_dims), (N, m)
        Frames the map is fitted on.
    Fy_val, Fx_val : ndarray of shape (n, >= n_dims), (n, m)
        Validation frames (never the frames scored later).
    n_dims : int
    candidates : sequence of int
        k tried (those outside ``n_dims + 2 .. N`` are skipped).

    Returns
    -------
    k : int
    errors : dict of int to float
        RMS Euclidean error in X per k tried.
    """
    errors = {}
    for k in candidates:
        if not int(n_dims) + 2 <= int(k) <= len(Fy_fit):
            continue
        m = LocalLinearInverse(n_neighbors=int(k), n_dims=int(n_dims)).fit(Fy_fit, Fx_fit)
        e = np.linalg.norm(m.transform(Fy_val) - np.asarray(Fx_val, dtype=np.float64), axis=1)
        errors[int(k)] = float(np.sqrt((e ** 2).mean()))
    if not errors:
        raise ValueError(f"no candidate k in {list(candidates)} fits {len(Fy_fit)} frames in {n_dims} dims")
    return min(errors, key=errors.__getitem__), errors

"""Gap trajectories learnt from the training trajectories between two points of the manifold.

The maximum-probability state path of exactly a gap's length (paper 4.1) is not the path
a real trajectory between two targets takes. Here the training data say which path that
is: for a gap of ``n`` frames from a point ``a`` of F^y (a target state's centroid) to a
point ``b``, the *candidate* sub-trajectories of the training utterances are those that
start among the ``n_pool`` frames nearest ``a`` or end among those nearest ``b``, and
last ``L`` frames with ``n / (1 + r) <= L <= n (1 + r)`` (``r`` the
``duration_tolerance``). Each is scored by::

    (|F^y_start - a|^2 + |F^y_end - b|^2) / s2 + (log(L / n) / log(1 + r))^2

(``s2`` the mean squared distance of a training frame from its state's centroid, so a
state's own spread costs 1), time-warped linearly onto the gap's ``n + 1`` frames, and
the ``k`` best are averaged in X with weights ``exp(-(score - best) / h)`` (``h`` the
median score of the ``k`` above the best): :meth:`LearntPaths.gap_means` gives that mean
for several ``k`` at once. A segment never crosses an utterance boundary.

How much of that pooled path a synthesiser should use, per shape component, is a
question for validation data (:func:`fit_blend`): a trajectory is a *base* interpolation
through the targets -- the state-velocity Hermite spline, PCHIP, linear or the Hermite
spline with calibrated velocities (:mod:`engine.synthesis.calibration`), whichever
validates best for that component -- plus ``beta_j`` times the pooled path's deviation
from it, component ``j`` pooling ``k_j`` neighbours (:func:`blend`). Components the
manifold carries (opening, rounding) keep close to the states; components it hardly
carries pool many neighbours, where the states' own means are noisy estimates; where the
states' velocities mislead (little training speech), a base without them takes over.
Given the validation utterances one by one, :func:`fit_blend` chooses each component's
base and ``k`` by their error on each utterance with ``beta`` fitted on the others, so a
handful of validation utterances cannot buy a flexible blend that only fits themselves.
Without validation data the base is the calibrated spline (:func:`prior_blend`).
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np
from scipy.spatial import cKDTree

from engine.constraints import Interval, validate_params
from engine.estimator import Estimator, check_is_fitted

__all__ = ["prior_blend", "LearntPaths", "NEIGHBOR_STEPS", "BASES", "PRIOR_BASE", "blend", "fit_blend",
           "BlendAccumulator"]

#: numbers of pooled neighbour paths a component may use (chosen per component on validation)
NEIGHBOR_STEPS = (8, 16, 32, 64, 128, 256)
#: base interpolations through the targets a component may build on (chosen per component on validation):
#: the state-velocity Hermite spline, PCHIP, linear, and the Hermite spline with calibrated velocities
BASES = ("hermite", "pchip", "linear", "calibrated")
#: the base where there is no validation data
PRIOR_BASE = BASES.index("calibrated")


class LearntPaths(Estimator):
    """Training sub-trajectories between the neighbourhoods of two points of F^y.

    Parameters
    ----------
    n_pool : int, default=128
        Frames nearest each end point from which candidate segments start (or end).
    duration_tolerance : float, default=0.35
        r: candidate segments last between n / (1 + r) and n (1 + r) frames.
    max_neighbors : int, default=256
        Most candidates pooled (the largest ``k`` of :meth:`gap_means`).

    Use ``fit(Fy, Fx, bounds, labels, centroids)``: the training frames' F^y (N, >= d),
    their F^x (N, m), the utterance bounds (U, 2), their state labels (N,) and the state
    centroids (K, d), which fix d.

    Attributes
    ----------
    n_dims_ : int
    scale_ : float
        s2, the mean squared distance of a training frame from its state's centroid.
    """

    _parameter_constraints = {
        "n_pool": [Interval(Integral, 1, None, closed="left")],
        "duration_tolerance": [Interval(Real, 0, None, closed="neither")],
        "max_neighbors": [Interval(Integral, 1, None, closed="left")],
    }

    def __init__(self, *, n_pool=128, duration_tolerance=0.35, max_neighbors=256):
        self.n_pool = n_pool
        self.duration_tolerance = duration_tolerance
        self.max_neighbors = max_neighbors

    def fit(self, Fy, Fx, bounds, labels, centroids):
        validate_params(self)
        C = np.asarray(centroids, dtype=np.float64)
        d = C.shape[1]
        Fy = np.asarray(Fy, dtype=np.float64)
        if Fy.ndim != 2 or Fy.shape[1] < d:
            raise ValueError(f"F^y must be (N, >= {d}) for {d}-D state centroids, got shape {Fy.shape}")
        Fx = np.asarray(Fx, dtype=np.float64)
        if Fx.shape[0] != Fy.shape[0]:
            raise ValueError(f"F^y has {Fy.shape[0]} rows but F^x has {Fx.shape[0]}; give one F^x per frame")
        lab = np.asarray(labels, dtype=np.int64)
        self._Y = np.ascontiguousarray(Fy[:, :d])
        self._X = Fx
        self._tree = cKDTree(self._Y)
        N = Fy.shape[0]
        self._start = np.zeros(N, dtype=np.int64)
        self._end = np.zeros(N, dtype=np.int64)
        for a, b in np.asarray(bounds, dtype=np.int64):
            self._start[a:b], self._end[a:b] = a, b
        self.n_dims_ = d
        self.scale_ = float(max(np.mean(((self._Y - C[lab]) ** 2).sum(axis=1)), 1e-12))
        self._cache = {}
        return self

    def _candidates(self, a, b, n):
        """Candidate (start, end, score) sorted by score, at most ``max_neighbors``."""
        r = float(self.duration_tolerance)
        Ls = np.arange(max(1, int(np.floor(n / (1 + r)))), int(np.ceil(n * (1 + r))) + 1)
        k1 = min(int(self.n_pool), self._Y.shape[0])
        S = np.asarray(self._tree.query(a, k=k1)[1]).reshape(-1)
        E = np.asarray(self._tree.query(b, k=k1)[1]).reshape(-1)
        s1 = np.repeat(S, Ls.size)
        e1 = s1 + np.tile(Ls, S.size)
        ok1 = e1 < self._end[s1]
        e2 = np.repeat(E, Ls.size)
        s2 = e2 - np.tile(Ls, E.size)
        ok2 = s2 >= self._start[e2]
        s = np.concatenate([s1[ok1], s2[ok2]])
        L = np.concatenate([e1[ok1] - s1[ok1], e2[ok2] - s2[ok2]])
        if s.size == 0:
            return None
        key = np.unique(s * (int(Ls[-1]) + 1) + L)
        s, L = key // (int(Ls[-1]) + 1), key % (int(Ls[-1]) + 1)
        e = s + L
        score = (((self._Y[s] - a) ** 2).sum(axis=1) + ((self._Y[e] - b) ** 2).sum(axis=1)) / self.scale_
        score += (np.log(L / n) / np.log1p(r)) ** 2
        order = np.argsort(score, kind="stable")[: int(self.max_neighbors)]
        return s[order], e[order], score[order]

    def gap_means(self, a, b, n, neighbors=NEIGHBOR_STEPS) -> np.ndarray | None:
        """Pooled paths from point ``a`` to point ``b`` over ``n`` transitions (``n + 1`` frames).

        Parameters
        ----------
        a, b : ndarray of shape (d,)
        n : int >= 1
        neighbors : sequence of int
            k of each mean (capped at the candidates found).

        Returns
        -------
        ndarray of shape (len(neighbors), n + 1, m), or None when no training segment fits.
        """
        check_is_fitted(self, "scale_")
        n = int(n)
        if n < 1:
            raise ValueError(f"a gap needs at least one transition, got n={n}")
        a = np.asarray(a, dtype=np.float64).reshape(-1)[: self.n_dims_]
        b = np.asarray(b, dtype=np.float64).reshape(-1)[: self.n_dims_]
        key = (a.tobytes(), b.tobytes(), n, tuple(int(k) for k in neighbors))
        if key in self._cache:
            return self._cache[key]
        c = self._candidates(a, b, n)
        if c is None:
            return None
        s, e, score = c
        pos = s[:, None] + (e - s)[:, None] * (np.arange(n + 1) / n)[None, :]
        f0 = np.floor(pos).astype(np.int64)
        f1 = np.minimum(f0 + 1, e[:, None])
        w = (pos - f0)[..., None]
        seg = (1.0 - w) * self._X[f0] + w * self._X[f1]  # (c, n + 1, m)
        W = np.zeros((len(neighbors), score.size))
        for i, k in enumerate(neighbors):
            k = max(1, min(int(k), score.size))
            sc = score[:k]
            h = max(float(np.median(sc) - sc[0]), 1e-9)
            W[i, :k] = np.exp(-(sc - sc[0]) / h)
        W /= W.sum(axis=1, keepdims=True)
        out = (W @ seg.reshape(score.size, -1)).reshape(len(neighbors), n + 1, -1)
        res = out
        if len(self._cache) > 4096:
            self._cache.clear()
        self._cache[key] = res
        return res

    def pooled(self, frames, points, n_frames, neighbors=NEIGHBOR_STEPS, x_targets=None, fallback=None) -> np.ndarray:
        """Pooled paths through timed targets, gap by gap: (len(neighbors), n_frames, m).

        A frame shared by two gaps takes the mean of their two ends. With ``x_targets``
        (T, m) each gap's path is pulled onto them (the residuals at its two ends
        interpolated linearly over the gap). A gap no training segment fits takes
        ``fallback`` (n_frames, m) there. The first target is held before it, the last after it.
        """
        check_is_fitted(self, "scale_")
        f = np.asarray(frames, dtype=np.int64)
        P = np.asarray(points, dtype=np.float64)
        m = self._X.shape[1]
        out = np.zeros((len(neighbors), int(n_frames), m))
        cnt = np.zeros(int(n_frames))
        if f.size == 1:
            X0 = (np.asarray(x_targets, np.float64)[0] if x_targets is not None else
                  self._X[int(self._tree.query(P[0, : self.n_dims_])[1])])
            out[:] = X0
            return out
        for g in range(f.size - 1):
            f0, f1 = int(f[g]), int(f[g + 1])
            n = f1 - f0
            G = self.gap_means(P[g], P[g + 1], n, neighbors)
            if G is None:
                if fallback is None:
                    raise ValueError(f"no training segment joins targets {g} and {g + 1} ({n} frames)")
                G = np.repeat(np.asarray(fallback, np.float64)[None, f0:f1 + 1], len(neighbors), axis=0)
            if x_targets is not None:
                xt = np.asarray(x_targets, dtype=np.float64)
                t = (np.arange(n + 1) / n)[None, :, None]
                G = G + (1 - t) * (xt[g] - G[:, :1]) + t * (xt[g + 1] - G[:, -1:])
            out[:, f0:f1 + 1] += G
            cnt[f0:f1 + 1] += 1
        lo, hi = int(f[0]), int(f[-1]) + 1
        out[:, lo:hi] /= cnt[None, lo:hi, None]
        out[:, :lo] = out[:, lo:lo + 1]
        out[:, hi:] = out[:, hi - 1:hi]
        return out


def blend(bases, pooled, base_index, neighbor_index, beta) -> np.ndarray:
    """``base[b_j] + beta_j (pooled[k_j] - base[b_j])`` per component j: (n, m).

    ``bases`` (len(BASES), n, m) (rows not chosen by any component may be zeros),
    ``pooled`` (len(neighbors), n, m), ``base_index``, ``neighbor_index`` and ``beta`` (m,).
    """
    B = np.asarray(bases, dtype=np.float64)
    m = B.shape[2]
    cols = np.arange(m)
    b = B[np.asarray(base_index, dtype=np.int64), :, cols].T  # (n, m)
    P = np.asarray(pooled, dtype=np.float64)[np.asarray(neighbor_index, dtype=np.int64), :, cols].T
    return b + np.asarray(beta, dtype=np.float64)[None, :] * (P - b)


class BlendAccumulator:
    """Sums over validation frames for :func:`fit_blend`: per (base, k, component) the products of
    D = pooled - base and R = truth - base."""

    def __init__(self, n_bases, n_neighbors, n_components):
        self.dd = np.zeros((n_bases, n_neighbors, n_components))
        self.dr = np.zeros((n_bases, n_neighbors, n_components))
        self.rr = np.zeros((n_bases, n_components))
        self.frames = 0

    def add(self, bases, pooled, truth):
        """One utterance's scored frames: bases (nb, n, m), pooled (nk, n, m), truth (n, m)."""
        B = np.asarray(bases, np.float64)
        P = np.asarray(pooled, np.float64)
        T = np.asarray(truth, np.float64)
        for i in range(B.shape[0]):
            D = P - B[i][None]
            R = T - B[i]
            self.dd[i] += (D ** 2).sum(axis=1)
            self.dr[i] += np.einsum("ktm,tm->km", D, R)
            self.rr[i] += (R ** 2).sum(axis=0)
        self.frames += T.shape[0]


def fit_blend(acc) -> dict:
    """Per component the base, k and beta in [0, 1] with the least squared error on the validation frames.

    For each base and k, beta = <D, R> / <D, D> clipped to [0, 1] (least squares). Given one
    :class:`BlendAccumulator` the (base, k) with the smallest error on its frames wins.
    Given one per validation utterance, each (base, k) -- and each base alone -- is scored
    by leave one utterance out: every utterance's error with beta fitted on the others,
    summed; the winner's beta is then fitted on all of them.

    Parameters
    ----------
    acc : BlendAccumulator or sequence of BlendAccumulator

    Returns
    -------
    dict
        ``base_index``, ``neighbor_index`` (m,) int into :data:`BASES` and the neighbour
        steps, ``beta`` (m,), ``sq_error`` (m,) the validation squared error per component
        (left out utterance by utterance where they were given one by one),
        ``sq_bases`` (len(BASES), m) that of each base alone, ``frames``.
    """
    parts = [acc] if isinstance(acc, BlendAccumulator) else list(acc)
    dd = np.stack([a.dd for a in parts])  # (U, nb, nk, m)
    dr = np.stack([a.dr for a in parts])
    rr = np.stack([a.rr for a in parts])  # (U, nb, m)
    DD, DR, RR = dd.sum(axis=0), dr.sum(axis=0), rr.sum(axis=0)
    beta = _share(DR, DD)
    nb, nk, m = DD.shape
    if len(parts) < 2:
        err = RR[:, None, :] - 2 * beta * DR + beta ** 2 * DD  # (nb, nk, m)
    else:
        out = _share(DR[None] - dr, DD[None] - dd)  # each utterance's beta, fitted on the others
        err = (rr[:, :, None, :] - 2 * out * dr + out ** 2 * dd).sum(axis=0)
        err = np.concatenate([err, RR[:, None, :]], axis=1)  # slot nk: the base alone (beta 0)
    width = err.shape[1]
    flat = err.reshape(nb * width, m)
    best = np.argmin(flat, axis=0)
    b, k = best // width, best % width
    cols = np.arange(m)
    alone = k == nk
    k = np.where(alone, 0, k)
    return {"base_index": b.astype(int).tolist(), "neighbor_index": k.astype(int).tolist(),
            "beta": np.where(alone, 0.0, beta[b, k, cols]).tolist(), "sq_error": flat[best, cols].tolist(),
            "sq_bases": RR.tolist(), "frames": int(sum(a.frames for a in parts))}


def _share(dr, dd):
    """beta = dr / dd clipped to [0, 1] (0 where dd is 0)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.clip(np.where(dd > 0, dr / dd, 0.0), 0.0, 1.0)


def prior_blend(m) -> dict:
    """Blend weights without validation data: every component the calibrated spline (:data:`PRIOR_BASE`),
    no learnt share."""
    return {"base_index": [PRIOR_BASE] * int(m), "neighbor_index": [0] * int(m), "beta": [0.0] * int(m),
            "sq_error": None, "sq_bases": None, "frames": 0}

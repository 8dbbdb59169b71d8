"""Cohen & Massaro (1993) coarticulation by dominance functions: shape from phones and their times.

Each phone type ``s`` has a target ``T_s`` in the shape space X and a dominance over
time: ``D_s(tau) = alpha_s exp(-theta_s |tau|^c)``, ``tau`` the time from the phone's
mid-point in seconds, with one rate ``theta`` before the mid-point (anticipation) and one
after (carry-over). A frame's shape is the dominance-weighted mean of the targets of the
phones around it:

    X(t) = sum_j D_j(t) T_j / sum_j D_j(t)      (the ``window`` phones either side of t's phone)

Fitting on training utterances (phones and their X): for given dominance parameters the
targets are a ridge least-squares solution (a K x K system, K phone types); the
dominance parameters (log alpha, log theta before / after per phone type, one log c) then
follow by L-BFGS on the squared error with the targets profiled out (their optimum makes
the gradient the partial one). The model the synthetic talker is generated with is of
this family (per control, not per shape component), so on that talker this is a strong
baseline, not a straw man. :class:`engine.synthesis.trajectory.PhoneModelSynthesizer` puts it behind the
synthesiser interface (method ``"dominance"``).
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np
import scipy.sparse as sp

from engine.constraints import Interval, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.threads import single_blas_thread

__all__ = ["DominanceModel"]

#: bounds of the log parameters: alpha, theta (1/s^c), c
_LOG_ALPHA = (-6.0, 6.0)
_LOG_THETA = (np.log(0.1), np.log(500.0))
_LOG_C = (np.log(0.5), np.log(3.0))


class DominanceModel(Estimator):
    """Phone targets in X blended by Cohen-Massaro dominance functions.

    Parameters
    ----------
    window : int, default=4
        Phones either side of a frame's own phone whose dominance reaches it.
    ridge : float, default=1e-3
        Ridge pulling each target towards the mean frame, relative to the mean diagonal
        of the normal equations (keeps rare phones' targets finite).
    max_iter : int, default=200
        L-BFGS iterations.

    Use ``fit(sequences, rate)`` with ``sequences`` a list of (X (n, m), phones), then
    ``predict(phones, n_frames, rate)``.

    Attributes
    ----------
    labels_ : list of str
        Phone types, most frequent first.
    targets_ : ndarray of shape (K, m)
    alpha_, theta_before_, theta_after_ : ndarray of shape (K,)
    c_ : float
    loss_ : float
        Mean squared error per frame on the training frames.
    """

    _parameter_constraints = {
        "window": [Interval(Integral, 0, None, closed="left")],
        "ridge": [Interval(Real, 0, None, closed="left")],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
    }

    def __init__(self, *, window=4, ridge=1e-3, max_iter=200):
        self.window = window
        self.ridge = ridge
        self.max_iter = max_iter

    # ------------------------------------------------------------------ layout
    def _layout(self, phones_list, n_list, rate, index):
        """Per frame: the window's phone types and times from their mid-points (N, W) with a mask."""
        W = 2 * int(self.window) + 1
        types, taus, masks = [], [], []
        for phones, n in zip(phones_list, n_list):
            mids = np.array([p.mid for p in phones])
            starts = np.array([p.start for p in phones])
            ty = np.array([index[p.label] for p in phones], dtype=np.int64)
            t = np.arange(int(n)) / float(rate)
            own = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(phones) - 1)
            j = own[:, None] + np.arange(-int(self.window), int(self.window) + 1)[None, :]
            ok = (j >= 0) & (j < len(phones))
            jc = np.clip(j, 0, len(phones) - 1)
            types.append(np.where(ok, ty[jc], 0))
            taus.append(np.where(ok, t[:, None] - mids[jc], 0.0))
            masks.append(ok)
        if not types:
            return np.zeros((0, W), np.int64), np.zeros((0, W)), np.zeros((0, W), bool)
        return np.vstack(types), np.vstack(taus), np.vstack(masks)

    @staticmethod
    def _weights(p, types, taus, mask, K):
        """Normalised dominance (N, W) and the pieces of its derivative."""
        la, lb, lf, lc = p[:K], p[K:2 * K], p[2 * K:3 * K], p[3 * K]
        c = np.exp(lc)
        absx = np.maximum(np.abs(taus), 1e-6)
        theta = np.exp(np.where(taus < 0, lb[types], lf[types]))
        powc = absx ** c
        logD = la[types] - theta * powc
        logD = np.where(mask, logD, -np.inf)
        logD -= logD.max(axis=1, keepdims=True)
        D = np.exp(logD)
        w = D / D.sum(axis=1, keepdims=True)
        return w, theta * powc, np.log(absx)

    def _solve_targets(self, w, types, X, K):
        N, W = w.shape
        rows = np.repeat(np.arange(N), W)
        A = sp.csr_matrix((w.ravel(), (rows, types.ravel())), shape=(N, K))
        G = (A.T @ A).toarray()
        lam = float(self.ridge) * max(np.trace(G) / K, 1e-12)
        mu = X.mean(axis=0)
        T = np.linalg.solve(G + lam * np.eye(K), A.T @ X + lam * mu[None, :])
        return A, T, lam * float(((T - mu[None, :]) ** 2).sum())

    def _objective(self, p, types, taus, mask, X, K):
        w, tp, logx = self._weights(p, types, taus, mask, K)
        A, T, penalty = self._solve_targets(w, types, X, K)
        Xh = A @ T
        R = X - Xh
        N = X.shape[0]
        loss = (float((R ** 2).sum()) + penalty) / N  # the targets' own objective: its optimum profiles them out
        # dE/dw_tj (w normalised): -2 R_t . (T_j - Xh_t); through the normalisation,
        # dE/dlogD_tj = w_tj (g_tj - sum_k w_tk g_tk).
        # R_t . T_j is (R T^T)[t, type j]: (N, K) instead of the (N, W, m) of T[types] (1.8 GB at a million frames)
        RT = R @ T.T
        g = -2.0 * (np.take_along_axis(RT, types, axis=1) - np.einsum("tm,tm->t", R, Xh)[:, None]) / N
        gl = w * g  # dE/dlogD (the normalisation's term vanishes: sum_j w (T_j - Xh) = 0)
        gl = np.where(mask, gl, 0.0)
        grad = np.zeros_like(p)
        before = taus < 0
        grad[:K] = np.bincount(types.ravel(), weights=gl.ravel(), minlength=K)
        gt = -gl * tp
        grad[K:2 * K] = np.bincount(types[before], weights=gt[before], minlength=K)
        grad[2 * K:3 * K] = np.bincount(types[~before], weights=gt[~before], minlength=K)
        grad[3 * K] = float((gt * logx * np.exp(p[3 * K])).sum())
        return loss, grad

    # ------------------------------------------------------------------ API
    @single_blas_thread
    def fit(self, sequences, rate):
        """Fit targets and dominance on ``sequences``: list of (X (n, m), phones), at ``rate`` Hz."""
        from scipy.optimize import minimize

        validate_params(self)
        seqs = [(np.asarray(X, np.float64), tuple(ph)) for X, ph in sequences if len(ph)]
        if not seqs:
            raise ValueError("the dominance model needs phone-aligned utterances; none of the training "
                             "utterances has phones (import the corpus with an alignment)")
        from collections import Counter

        counts = Counter(p.label for _, ph in seqs for p in ph)
        self.labels_ = [lab for lab, _ in counts.most_common()]
        index = {lab: i for i, lab in enumerate(self.labels_)}
        K = len(self.labels_)
        X = np.vstack([x for x, _ in seqs])
        types, taus, mask = self._layout([ph for _, ph in seqs], [len(x) for x, _ in seqs], rate, index)
        p0 = np.concatenate([np.zeros(K), np.full(2 * K, np.log(10.0)), [0.0]])
        bounds = [_LOG_ALPHA] * K + [_LOG_THETA] * (2 * K) + [_LOG_C]
        res = minimize(self._objective, p0, args=(types, taus, mask, X, K), jac=True, method="L-BFGS-B",
                       bounds=bounds, options={"maxiter": int(self.max_iter)})
        p = res.x
        w, _, _ = self._weights(p, types, taus, mask, K)
        _, self.targets_, _ = self._solve_targets(w, types, X, K)
        self.alpha_ = np.exp(p[:K])
        self.theta_before_ = np.exp(p[K:2 * K])
        self.theta_after_ = np.exp(p[2 * K:3 * K])
        self.c_ = float(np.exp(p[3 * K]))
        self.loss_ = float(res.fun)
        return self

    def _packed(self) -> np.ndarray:
        """The log parameters (log alpha, log theta before, log theta after, log c) of the fitted model."""
        return np.concatenate([np.log(self.alpha_), np.log(self.theta_before_), np.log(self.theta_after_),
                               [np.log(self.c_)]])

    def predict(self, phones, n_frames, rate, warnings=None) -> np.ndarray:
        """X (n_frames, m) of phone intervals (seconds from 0); unknown phones get a stand-in."""
        check_is_fitted(self, "targets_")
        from engine.phonetics.targets import resolve_phone as _resolve_phone

        K = len(self.labels_)
        index = {lab: i for i, lab in enumerate(self.labels_)}
        phones = tuple(phones)
        if not phones:
            raise ValueError("the dominance model needs the phone intervals to synthesise")
        labs = [_resolve_phone(p.label, self.labels_, warnings, "dominance function") for p in phones]
        from dataclasses import replace

        ph = tuple(replace(p, label=lab) for p, lab in zip(phones, labs))
        types, taus, mask = self._layout([ph], [int(n_frames)], rate, index)
        w, _, _ = self._weights(self._packed(), types, taus, mask, K)  # the fitted attributes alone: a stored model
        return np.einsum("tw,twm->tm", w, self.targets_[types])

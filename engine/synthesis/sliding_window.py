"""Sliding-window regression from phone labels to shape (after Taylor et al. 2017).

Every frame ``t`` is described by the phone labels of the frames in a window around it:
the labels at ``t + o`` for ``o`` in ``-context, -context + step, ..., context`` frames,
one-hot (a boundary symbol beyond the utterance), concatenated. A regressor maps that to
the shape X of the ``output_window`` frames centred on ``t``; a frame's prediction is the
mean of the windows covering it (the overlap averaging of the paper). The paper's deep
network is stood in for by ridge regression (``"ridge"``, solved by its normal equations)
or scikit-learn's multi-layer perceptron (``"mlp"``). Fitted on training utterances only;
the window and the penalty are chosen on validation data.
:class:`engine.synthesis.trajectory.PhoneModelSynthesizer` puts it behind the synthesiser interface
(method ``"sliding-window"``).
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np
import scipy.sparse as sp

from engine.constraints import Condition, Interval, StrOptions, validate_params
from engine.estimator import Estimator, check_is_fitted

__all__ = ["SlidingWindowRegressor", "REGRESSORS"]

REGRESSORS = ("ridge", "mlp")
_BOUNDARY = "#"


class SlidingWindowRegressor(Estimator):
    """Phone-label windows -> shape windows, overlap-averaged.

    Parameters
    ----------
    context : int, default=12
        Input window half-width in frames.
    step : int, default=2
        Spacing of the input window's frames.
    output_window : int, default=5
        Frames of X predicted per window (odd).
    regressor : {"ridge", "mlp"}, default="ridge"
    alpha : float, default=1.0
        Ridge penalty (``"ridge"``) or L2 penalty (``"mlp"``).
    hidden : int, default=256
        Units of the perceptron's hidden layer.
    random_state : int, default=0

    Use ``fit(sequences, rate)`` with ``sequences`` a list of (X (n, m), phones), then
    ``predict(phones, n_frames, rate)``.
    """

    _parameter_constraints = {
        "context": [Interval(Integral, 0, None, closed="left")],
        "step": [Interval(Integral, 1, None, closed="left")],
        "output_window": [Condition(lambda n: Interval(Integral, 1, None, closed="left").is_satisfied_by(n)
                                    and n % 2 == 1, "an odd integer >= 1", bad=[0, 4, 2.5])],
        "regressor": [StrOptions(REGRESSORS)],
        "alpha": [Interval(Real, 0, None, closed="left")],
        "hidden": [Interval(Integral, 1, None, closed="left")],
        "random_state": ["random_state"],
    }

    def __init__(self, *, context=12, step=2, output_window=5, regressor="ridge", alpha=1.0, hidden=256,
                 random_state=0):
        self.context = context
        self.step = step
        self.output_window = output_window
        self.regressor = regressor
        self.alpha = alpha
        self.hidden = hidden
        self.random_state = random_state

    def _offsets(self):
        c, s = int(self.context), int(self.step)
        return np.arange(-(c // s) * s, c + 1, s)

    def _frame_labels(self, phones, n, rate, index):
        """Label index of each of ``n`` frames (boundary index where no phone covers it)."""
        lab = np.full(int(n), index[_BOUNDARY], dtype=np.int64)
        for p in phones:
            a = int(np.clip(round(p.start * rate), 0, n))
            b = int(np.clip(round(p.end * rate), 0, n))
            lab[a:b] = index[p.label]
        return lab

    def _features(self, lab):
        n = lab.size
        offs = self._offsets()
        V = len(self.vocabulary_)
        j = np.arange(n)[:, None] + offs[None, :]
        ok = (j >= 0) & (j < n)
        L = np.where(ok, lab[np.clip(j, 0, n - 1)], len(self.vocabulary_) - 1)  # the boundary label comes last
        cols = (np.arange(offs.size)[None, :] * V + L).ravel()
        rows = np.repeat(np.arange(n), offs.size)
        return sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n, offs.size * V))

    def _windows(self, X):
        """(n, output_window * m): X of the frames centred on each frame, held at the ends."""
        n = X.shape[0]
        h = int(self.output_window) // 2
        j = np.clip(np.arange(n)[:, None] + np.arange(-h, h + 1)[None, :], 0, n - 1)
        return X[j].reshape(n, -1)

    def fit(self, sequences, rate):
        from collections import Counter

        validate_params(self)
        seqs = [(np.asarray(X, np.float64), tuple(ph)) for X, ph in sequences if len(ph)]
        if not seqs:
            raise ValueError("sliding-window regression needs phone-aligned utterances; none of the training "
                             "utterances has phones (import the corpus with an alignment)")
        counts = Counter(p.label for _, ph in seqs for p in ph)
        self.labels_ = [lab for lab, _ in counts.most_common()]
        self.vocabulary_ = self.labels_ + [_BOUNDARY]
        index = {lab: i for i, lab in enumerate(self.vocabulary_)}
        feats, outs = [], []
        for X, ph in seqs:
            lab = self._frame_labels(ph, X.shape[0], rate, index)
            feats.append(self._features(lab))
            outs.append(self._windows(X))
        A, Y = sp.vstack(feats).tocsr(), np.vstack(outs)
        self.mean_ = Y.mean(axis=0)
        if self.regressor == "ridge":
            # ridge regression by its normal equations: the Gram matrix of the one-hot features is small
            # (window positions x labels), so one Cholesky solve serves every output column (scikit-learn's
            # Ridge takes seconds per fit here); each window position's one-hot block sums to 1, so the
            # centred outputs need no separate intercept
            from scipy.linalg import cho_factor, cho_solve

            G = (A.T @ A).toarray()
            G[np.diag_indices_from(G)] += float(self.alpha)
            self.coef_ = cho_solve(cho_factor(G), np.asarray(A.T @ (Y - self.mean_)))
            self.model_ = None
        else:
            from sklearn.neural_network import MLPRegressor

            self.scale_ = float(np.sqrt(((Y - self.mean_) ** 2).mean())) or 1.0
            self.model_ = MLPRegressor(hidden_layer_sizes=(int(self.hidden),), alpha=float(self.alpha),
                                       early_stopping=True, max_iter=200, random_state=self.random_state).fit(
                A, (Y - self.mean_) / self.scale_)
        self.n_components_ = seqs[0][0].shape[1]
        return self

    def predict(self, phones, n_frames, rate, warnings=None) -> np.ndarray:
        """X (n_frames, m) from phone intervals (seconds from 0); unknown phones get a stand-in."""
        check_is_fitted(self, "mean_")
        from dataclasses import replace

        from engine.phonetics.targets import resolve_phone as _resolve_phone

        phones = tuple(phones)
        if not phones:
            raise ValueError("sliding-window regression needs the phone intervals to synthesise")
        ph = tuple(replace(p, label=_resolve_phone(p.label, self.labels_, warnings, "instances")) for p in phones)
        index = {lab: i for i, lab in enumerate(self.vocabulary_)}
        n = int(n_frames)
        lab = self._frame_labels(ph, n, rate, index)
        A = self._features(lab)
        Y = np.asarray(A @ self.coef_) if self.model_ is None else self.model_.predict(A) * self.scale_
        Y = (Y + self.mean_).reshape(n, int(self.output_window), -1)
        h = int(self.output_window) // 2
        out = np.zeros((n, Y.shape[2]))
        cnt = np.zeros(n)
        for o in range(-h, h + 1):  # the window of frame t predicts frames t - h .. t + h
            t = np.arange(n) + o
            ok = (t >= 0) & (t < n)
            np.add.at(out, t[ok], Y[ok, o + h])
            np.add.at(cnt, t[ok], 1.0)
        return out / cnt[:, None]

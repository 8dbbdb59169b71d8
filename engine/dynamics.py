"""Dynamic features G = [alpha (F^x - mu), beta (F^x' - mu')] (paper section 3.1).

Velocities never cross an utterance boundary: inside each utterance
F^x'_i = F^x_i - F^x_{i-1}, and the first frame uses F^x_1 - F^x_0. Each block is
centred on its mean and scaled by **one scalar** so that its largest absolute entry
is 1; per-component scaling would break the dominance of component 1 that the
manifold's structure relies on.
"""
from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

__all__ = ["velocities", "check_bounds", "DynamicFeatures"]


def check_bounds(bounds, n_frames: int) -> np.ndarray:
    """Validate utterance bounds: int (U, 2) contiguous ``[start, stop)`` covering 0..n_frames."""
    b = np.asarray(bounds, dtype=np.int64)
    if b.ndim != 2 or b.shape[1] != 2 or len(b) == 0:
        raise ValueError(f"bounds must be an (n_utterances, 2) array of [start, stop), got shape {b.shape}")
    if b[0, 0] != 0 or b[-1, 1] != n_frames or np.any(b[1:, 0] != b[:-1, 1]) or np.any(b[:, 1] <= b[:, 0]):
        raise ValueError(
            f"bounds must be contiguous non-empty ranges covering frames 0..{n_frames}; got {b[:3].tolist()}..."
        )
    return b


def velocities(Fx, bounds) -> np.ndarray:
    """First differences inside each utterance.

    Parameters
    ----------
    Fx : ndarray of shape (N, m)
    bounds : ndarray of shape (U, 2)

    Returns
    -------
    Fxv : ndarray of shape (N, m), float32
        ``Fx[i] - Fx[i-1]``; the first frame of each utterance copies its second frame's
        difference (``Fx[1] - Fx[0]``); a one-frame utterance has zero velocity.
    """
    Fx = np.asarray(Fx, dtype=np.float32)
    b = check_bounds(bounds, Fx.shape[0])
    V = np.empty_like(Fx)
    V[1:] = Fx[1:] - Fx[:-1]
    starts, stops = b[:, 0], b[:, 1]
    long = stops - starts >= 2
    V[starts[long]] = V[starts[long] + 1]
    V[starts[~long]] = 0.0
    return V


class DynamicFeatures(BaseEstimator):
    """Scaled shape + velocity features.

    Attributes
    ----------
    mean_ : ndarray of shape (m,)
        mu, mean of F^x.
    velocity_mean_ : ndarray of shape (m,)
        mu', mean of F^x'.
    alpha_, beta_ : float
        Scalars making ``max |alpha (F^x - mu)| = 1`` and ``max |beta (F^x' - mu')| = 1``.
    """

    def fit(self, Fx, bounds):
        """Fit mu, mu', alpha, beta from F^x (N, m) and utterance bounds (U, 2)."""
        Fx = np.asarray(Fx, dtype=np.float32)
        if Fx.ndim != 2 or Fx.shape[0] < 2:
            raise ValueError(f"F^x must be (N >= 2, m), got shape {Fx.shape}")
        V = velocities(Fx, bounds)
        self.mean_ = Fx.mean(axis=0, dtype=np.float64).astype(np.float32)
        self.velocity_mean_ = V.mean(axis=0, dtype=np.float64).astype(np.float32)
        ax = float(np.abs(Fx - self.mean_).max())
        av = float(np.abs(V - self.velocity_mean_).max())
        if ax == 0 or av == 0:
            raise ValueError("the lips never move in this corpus (F^x or its velocity is constant); "
                             "nothing to embed")
        self.alpha_ = 1.0 / ax
        self.beta_ = 1.0 / av
        return self

    def transform_pair(self, Fx, Fxv) -> np.ndarray:
        """G from shape and velocity: ndarrays (n, m) each -> (n, 2m) float32."""
        check_is_fitted(self, "alpha_")
        Fx = np.asarray(Fx, dtype=np.float32)
        Fxv = np.asarray(Fxv, dtype=np.float32)
        m = self.mean_.shape[0]
        if Fx.shape != Fxv.shape or Fx.ndim != 2 or Fx.shape[1] != m:
            raise ValueError(f"F^x and F^x' must both be (n, {m}); got {Fx.shape} and {Fxv.shape}")
        return np.hstack([np.float32(self.alpha_) * (Fx - self.mean_),
                          np.float32(self.beta_) * (Fxv - self.velocity_mean_)])

    def transform(self, Fx, bounds) -> np.ndarray:
        """G for frames F^x (N, m) with utterance bounds (U, 2) -> (N, 2m)."""
        return self.transform_pair(Fx, velocities(Fx, bounds))

"""Utterance bounds: their validation, and first differences that never cross an utterance.

Velocities never cross an utterance boundary: inside each utterance
F^x'_i = F^x_i - F^x_{i-1}, and the first frame uses F^x_1 - F^x_0.
"""
from __future__ import annotations

import numpy as np

__all__ = ["check_bounds", "velocities"]


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

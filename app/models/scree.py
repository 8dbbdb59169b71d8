"""The scree of X and Y: the numbers the scree panel plots (Qt-free)."""
from __future__ import annotations

import numpy as np

__all__ = ["scree_series"]


def scree_series(manifold) -> dict:
    """The numbers the panel plots: per-component and cumulative explained variance of X and Y.

    Returns dict with ``x``, ``x_cum`` (from ``shape_.scree_``, of the total variance of F)
    and ``y``, ``y_cum`` (from ``embedding_.explained_variance_ratio_``), each ndarray.
    """
    x = np.asarray(manifold.shape_.scree_, dtype=np.float64)
    y = np.asarray(manifold.embedding_.explained_variance_ratio_, dtype=np.float64)
    return {"x": x, "x_cum": np.cumsum(x), "y": y, "y_cum": np.cumsum(y)}

"""How far a synthetic trajectory is from the real lips, and where it runs in Y.

:func:`trajectory_errors` scores a synthetic X trajectory against the real frames it
stands for (RMSE in X, mean and largest per-point error in the corpus's units): the
trajectory editor's error readout. :func:`trajectory_y` gives a synthetic trajectory
in the first dimensions of Y, the manifold the paper draws (its Fig. 3): the state
path of a method that moves in Y, the out-of-sample projection
(:func:`engine.manifold.model.project_x`) of any other.
"""
from __future__ import annotations

import numpy as np

from engine.manifold.model import project_x

__all__ = ["trajectory_errors", "trajectory_y", "Y_DIMS"]

#: dimensions of Y drawn and scored by default: the 3-D manifold of the paper's figures
Y_DIMS = 3


def trajectory_errors(manifold, Fx_hat, frames) -> dict:
    """Errors of a synthetic trajectory against the real frames it stands for.

    Parameters
    ----------
    manifold : Manifold
        Fitted; its shape space defines X.
    Fx_hat : ndarray of shape (n, m)
        Synthetic shape coordinates.
    frames : ndarray of shape (n, C)
        The real frames.

    Returns
    -------
    dict
        ``rmse_x`` (root mean square over frames of the Euclidean error in X),
        ``mean_point_error`` and ``max_point_error`` (Euclidean per point, corpus units),
        ``frames``.
    """
    dims = manifold.corpus_.dims
    Fx_hat = np.asarray(Fx_hat)
    frames = np.asarray(frames)
    X_true = manifold.shape_.transform(frames).astype(np.float64)
    err_x = np.linalg.norm(Fx_hat.astype(np.float64) - X_true, axis=1)
    n = frames.shape[0]
    F_hat = manifold.shape_.inverse_transform(Fx_hat).astype(np.float64).reshape(n, -1, dims)
    err_p = np.linalg.norm(F_hat - frames.astype(np.float64).reshape(n, -1, dims), axis=2)
    return {"rmse_x": float(np.sqrt((err_x ** 2).mean())), "mean_point_error": float(err_p.mean()),
            "max_point_error": float(err_p.max()), "frames": int(err_x.size)}


def trajectory_y(manifold, trajectory, dims=Y_DIMS) -> np.ndarray:
    """A synthetic trajectory in the first ``dims`` dimensions of Y, frame by frame.

    A trajectory that moves in Y (the manifold method) is its own path: the state
    centroids, before any inverse map (if the states were clustered in fewer than
    ``dims`` dimensions, each state's mean F^y over its members stands in). Any other
    (it moves in X) is projected out-of-sample with :func:`engine.manifold.model.project_x`.

    Parameters
    ----------
    manifold : Manifold
        Fitted.
    trajectory : Trajectory
    dims : int, default=3

    Returns
    -------
    ndarray of shape (n, dims), float64
    """
    dims = min(int(dims), manifold.Fy_.shape[1])
    if trajectory.Fy is not None and trajectory.Fy.shape[1] >= dims:
        return np.asarray(trajectory.Fy[:, :dims], dtype=np.float64)
    if trajectory.Fy is not None and trajectory.states is not None:
        lab = np.asarray(manifold.states_.labels_)
        K = int(manifold.states_.centroids_.shape[0])
        n = np.maximum(np.bincount(lab, minlength=K), 1)
        Fy = np.asarray(manifold.Fy_[:, :dims], dtype=np.float64)
        means = np.stack([np.bincount(lab, weights=Fy[:, j], minlength=K) for j in range(dims)], 1) / n[:, None]
        return means[np.asarray(trajectory.states)]
    return project_x(manifold, trajectory.Fx)[:, :dims].astype(np.float64)

"""Virtual articulograph sensors on the talker's lip surface, and the scree of a few sensors.

A real articulograph (EMA) records a handful of points on the lips and jaw: the upper and
lower lip on the midline at the vermilion border (UL, LL), a mouth corner (ML for the
left one) and the jaw, on the lower incisors (JAW). :func:`virtual_sensors` picks the
points of :class:`engine.talker.lipmodel.LipModel`'s surface that play those roles, so the
synthetic talker and a real recording can be compared on the same footing: the
principal components of the same few sensors' coordinates
(:func:`sensor_scree`), and how far each sensor moves (:func:`sensor_motion`). The scree
and the movement of 3-D points does not depend on how each recording
orients its axes (a rotation or a permutation of every sensor's x, y, z is an orthogonal
map of the coordinate vector), so the two need no common frame of reference.
"""
from __future__ import annotations

import numpy as np

__all__ = ["SENSOR_ROLES", "virtual_sensors", "sensor_scree", "sensor_motion"]

#: the sensors compared, in order: upper lip, lower lip, left mouth corner, jaw
SENSOR_ROLES = ("UL", "LL", "ML", "JAW")


def virtual_sensors(lip) -> dict[str, int]:
    """Point indices of the lip surface that play the articulograph's sensors.

    Parameters
    ----------
    lip : engine.talker.lipmodel.LipModel

    Returns
    -------
    dict
        ``{"UL": i, "LL": i, "ML": i, "JAW": i}``: the upper and lower lip on the midline
        at the vermilion border, the left corner (the inner contour's point nearest the
        commissure, on the talker's left, +x), and the chin's midline point at the grid's
        lower edge, which moves rigidly with the jaw.
    """
    R, C = lip.rows, lip.cols
    mid, border, corner = C // 2, lip.border_row, lip.corner_column
    return {"UL": border * C + mid, "LL": R * C + border * C + mid, "ML": corner, "JAW": R * C + (R - 1) * C + mid}


def sensor_scree(frames, points, *, fractions=(0.80, 0.90, 0.95)) -> dict:
    """Principal components of a few points' coordinates.

    Parameters
    ----------
    frames : array-like of shape (n_frames, 3 * n_points)
        Coordinates interleaved per point (x0, y0, z0, x1, ...).
    points : sequence of int
        The points compared (e.g. ``virtual_sensors(lip).values()``), at least two.
    fractions : sequence of float in (0, 1]

    Returns
    -------
    dict
        ``components`` (how many leading components reach each fraction of the variance)
        and ``scree`` (each component's fraction of the variance, largest first).
    """
    from engine.talker.report import components_for

    X = _centred(frames, points)
    ev = np.linalg.svd(X, compute_uv=False) ** 2
    if not ev.sum() > 0:
        raise ValueError("the sensors do not move (zero variance)")
    return {"components": components_for(ev, fractions), "scree": [float(v) for v in ev / ev.sum()]}


def sensor_motion(frames, points, *, dims: int = 3) -> np.ndarray:
    """How far each point moves: the root-mean-square distance from its mean position.

    Parameters
    ----------
    frames : array-like of shape (n_frames, dims * n_points)
    points : sequence of int
        At least two point indices.
    dims : {2, 3}
        Coordinates per point (2 for a midsagittal articulograph).

    Returns
    -------
    ndarray of shape (len(points),)
        Per point, the square root of the trace of its coordinates' covariance (mm if the
        frames are). It does not depend on how the axes are oriented, so recordings in
        different frames of reference compare directly.
    """
    X = _centred(frames, points, dims=dims)
    return np.sqrt((X ** 2).mean(0).reshape(-1, dims).sum(1))


def _centred(frames, points, *, dims=3):
    """The points' coordinates (n_frames, dims * len(points)) float64 minus their mean; checked."""
    F = np.asarray(frames)
    pts = [int(p) for p in points]
    if F.ndim != 2 or F.shape[1] % dims or len(F) < 3:
        raise ValueError(f"frames must have shape (n_frames >= 3, {dims} * n_points), got {F.shape}")
    n_points = F.shape[1] // dims
    if len(pts) < 2 or min(pts) < 0 or max(pts) >= n_points:
        raise ValueError(f"points must be at least two indices in 0..{n_points - 1}, got {pts}")
    cols = np.array([dims * p + d for p in pts for d in range(dims)])
    X = F[:, cols].astype(np.float64)
    if not np.isfinite(X).all():
        bad = int(np.flatnonzero(~np.isfinite(X).all(1))[0])
        raise ValueError(f"frame {bad} of the sensors' coordinates is NaN or inf; drop or fill such frames first")
    return X - X.mean(0)

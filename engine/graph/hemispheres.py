"""Hemispheres within a time horizon: which states can follow (or precede) a state soon.

The paper (Sec. 3, Fig. 2b) reads the future of a state F_i^y off the directed state
graph: the states at hop distance 1 are its possible next states, and the states
reachable at all form its future hemisphere (over A^T, its past hemisphere). On a
corpus of connected speech the graph is strongly connected, so every state is
reachable and "reachable" alone separates nothing. A time horizon restores the
reading: a hop joins the states of two consecutive frames, so within ``T`` seconds
at the corpus frame rate at most ``floor(T * rate)`` hops can be made, and the
states within that many hops are the ones that can follow within ``T``.

Pure numpy; the explorer colours its points from these numbers.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["DIRECTIONS", "horizon_hops", "horizon_seconds", "directed_hops", "Hemisphere", "hemisphere"]

DIRECTIONS = ("future", "past", "both")


def horizon_hops(horizon_s: float, rate: float) -> int:
    """Largest number of hops that fit in ``horizon_s`` seconds at ``rate`` frames per second.

    One hop joins the states of two consecutive frames, so it takes at least one frame
    period ``1 / rate``; ``floor(horizon_s * rate)`` (with a tolerance of 1e-9 hop so that
    a horizon of exactly k frames gives k hops).

    Parameters
    ----------
    horizon_s : float
        Horizon in seconds, >= 0.
    rate : float
        Corpus frame rate in frames per second, > 0.

    Returns
    -------
    int
    """
    horizon_s, rate = float(horizon_s), float(rate)
    if not np.isfinite(horizon_s) or horizon_s < 0:
        raise ValueError(f"horizon must be a finite number of seconds >= 0, got {horizon_s!r}")
    if not np.isfinite(rate) or rate <= 0:
        raise ValueError(f"frame rate must be a positive number of frames per second, got {rate!r}")
    return int(np.floor(horizon_s * rate + 1e-9))


def horizon_seconds(hops: int, rate: float) -> float:
    """The shortest time in which ``hops`` hops can be made at ``rate`` frames per second."""
    hops, rate = int(hops), float(rate)
    if hops < 0:
        raise ValueError(f"hops must be >= 0, got {hops}")
    if not np.isfinite(rate) or rate <= 0:
        raise ValueError(f"frame rate must be a positive number of frames per second, got {rate!r}")
    return hops / rate


def directed_hops(graph: Any, state: int, direction: str) -> np.ndarray:
    """Directed hop distance of every state from ``state`` (future) or to it (past).

    Parameters
    ----------
    graph : engine.graph.states.StateGraph, fitted
    state : int
    direction : {"future", "past"}

    Returns
    -------
    ndarray of shape (K,) float64
        0 at ``state``, ``inf`` where unreachable.
    """
    if direction == "future":
        return np.asarray(graph.future(state), dtype=np.float64)
    if direction == "past":
        return np.asarray(graph.past(state), dtype=np.float64)
    raise ValueError(f"direction must be 'future' or 'past', got {direction!r}")


class Hemisphere:
    """The future and/or past hemisphere of one state within a hop horizon, per frame.

    Attributes
    ----------
    hops : ndarray of shape (N,) float32
        Signed hop distance of each frame's state: ``+d`` in the future hemisphere,
        ``-d`` in the past one (0 for the state itself), NaN outside the horizon or
        unreachable. With ``direction="both"`` a state reachable both ways takes the
        nearer side (the future on a tie).
    inside : ndarray of shape (N,) bool
        Frames within the horizon.
    reachable : ndarray of shape (N,) bool
        Frames whose state is reachable at all (in ``direction``), within the horizon or not.
    max_hops : int or None
        The horizon in hops (None: unlimited).
    direction : str
    fraction_inside : float
        ``inside.mean()`` (0 for no frames).
    reach : int
        The largest hop distance of a reachable state (the hemisphere's depth without horizon).
    weights : ndarray of shape (N,) or None
        Frames each entry stands for (None: one each); ``fraction_inside`` and
        ``n_inside`` count frames.
    """

    def __init__(self, hops: np.ndarray, inside: np.ndarray, reachable: np.ndarray, max_hops: int | None,
                 direction: str, reach: int, weights: np.ndarray | None = None) -> None:
        self.hops = hops
        self.inside = inside
        self.reachable = reachable
        self.max_hops = max_hops
        self.direction = direction
        self.reach = int(reach)
        self.weights = weights
        total = inside.size if weights is None else float(np.sum(weights))
        self.fraction_inside = self.n_inside / total if total else 0.0

    @property
    def n_inside(self) -> int:
        return int(self.inside.sum() if self.weights is None else np.sum(self.weights[self.inside]))


def hemisphere(graph: Any, state: int, labels: ArrayLike, *, direction: str = "future", max_hops: int | None = None,
               weights: ArrayLike | None = None) -> Hemisphere:
    """Frames whose state lies within ``max_hops`` hops after (and/or before) ``state``.

    Parameters
    ----------
    graph : engine.graph.states.StateGraph, fitted
    state : int
        The selected state.
    labels : ndarray of shape (N,) int
        The state of each frame (``graph.labels_`` for the corpus frames), or of each
        group of frames of one state (a drawn point standing for several frames).
    direction : {"future", "past", "both"}, default="future"
    max_hops : int or None, default=None
        Horizon in hops (see :func:`horizon_hops`); None = unlimited.
    weights : ndarray of shape (N,), optional
        Frames each entry of ``labels`` stands for (default one each), so that the
        fraction inside counts frames.

    Returns
    -------
    Hemisphere
    """
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be one of {DIRECTIONS}, got {direction!r}")
    if max_hops is not None:
        if isinstance(max_hops, (bool, np.bool_)) or int(max_hops) != max_hops or max_hops < 0:
            raise ValueError(f"max_hops must be a whole number of hops >= 0 or None, got {max_hops!r}")
        max_hops = int(max_hops)
    labels = np.asarray(labels)
    fut = directed_hops(graph, state, "future") if direction in ("future", "both") else None
    past = directed_hops(graph, state, "past") if direction in ("past", "both") else None
    if direction == "future":
        assert fut is not None
        signed = fut.copy()
    elif direction == "past":
        assert past is not None
        signed = -past
    else:
        assert fut is not None and past is not None
        signed = np.where(past < fut, -past, fut)  # the nearer side; a tie (and the state itself) is future
    dist = np.abs(signed)
    finite = np.isfinite(dist)
    reach = int(dist[finite].max()) if finite.any() else 0
    keep = finite if max_hops is None else finite & (dist <= max_hops)
    per_state = np.where(keep, signed, np.nan)
    hops = per_state[labels].astype(np.float32)
    if weights is not None:
        weights = np.asarray(weights)
        if weights.shape != labels.shape:
            raise ValueError(f"weights must give one count per label, shape {labels.shape}, got {weights.shape}")
    return Hemisphere(hops, keep[labels], finite[labels], max_hops, direction, reach, weights)

"""A lip trajectory as the explorer holds it: rows of F^y and F^x, and the captured one of an utterance."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["TrajectoryData", "original_trajectory"]


@dataclass(frozen=True)
class TrajectoryData:
    """A lip trajectory in the embedding and in the shape space.

    Parameters
    ----------
    Y : ndarray of shape (n, k)
        Positions in F^y (the first 3 columns are drawn).
    Fx : ndarray of shape (n, m) or None
        Shape coordinates, for the lip view (None: not available).
    frames : ndarray of shape (n,) int or None
        Corpus frame indices, for an original (captured) trajectory.
    label : str
        Utterance id or synthesis method.
    rate : float
        Frames per second.
    """

    Y: np.ndarray
    Fx: np.ndarray | None = None
    frames: np.ndarray | None = None
    label: str = ""
    rate: float = 60.0
    extra: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return int(np.asarray(self.Y).shape[0])


def original_trajectory(manifold, uid: str) -> TrajectoryData:
    """The captured trajectory of utterance ``uid``: its rows of F^y and F^x."""
    c = manifold.corpus_
    u = c.utterance(uid)
    idx = np.arange(u.start, u.stop)
    return TrajectoryData(Y=manifold.Fy_[idx], Fx=manifold.Fx_[idx], frames=idx, label=u.id, rate=c.rate)

"""Level of detail of the manifold cloud: which frames the explorer draws (issue 13 item 8).

A corpus of a million frames is more than a 3-D view can redraw interactively, and
more than the eye separates. The view draws every state (its centroid) and at most
``max_frames`` frames, chosen per state in proportion to its size so that the cloud
keeps its shape and density, with every state represented by at least one frame.
Below the cap every frame is drawn. The choice is deterministic (seeded), so the same
manifold always shows the same frames; selections stay frame indices (the picked
point's index in the drawn cloud maps back through the returned indices: the manifold
scene's ``PointsHandle.frame_of``).
"""
from __future__ import annotations

import numpy as np

__all__ = ["cloud_subsample", "cloud_frames", "DEFAULT_MAX_FRAMES"]

#: frames drawn at most (all of them below this)
DEFAULT_MAX_FRAMES = 150_000


def cloud_subsample(labels, *, max_frames: int = DEFAULT_MAX_FRAMES, random_state: int = 0) -> np.ndarray:
    """Indices of the frames to draw, stratified by state.

    Parameters
    ----------
    labels : ndarray of shape (N,), int
        State of each frame (``StateGraph.labels_``), values in 0..K-1.
    max_frames : int, default=DEFAULT_MAX_FRAMES
        Cap on the frames drawn. With N <= max_frames every frame is drawn. Above,
        state k keeps ``max(1, floor(max_frames * n_k / N))`` of its n_k frames, drawn
        at random, so at most ``max_frames + K`` frames are drawn.
    random_state : int, default=0

    Returns
    -------
    ndarray of shape (n,), int64
        Sorted frame indices (``arange(N)`` when nothing is dropped).
    """
    labels = np.asarray(labels)
    if labels.ndim != 1 or (labels.size and (not np.issubdtype(labels.dtype, np.integer) or labels.min() < 0)):
        raise ValueError(f"labels must be a 1-D array of state indices >= 0, got dtype {labels.dtype}, "
                         f"shape {labels.shape}")
    if isinstance(max_frames, bool) or not isinstance(max_frames, (int, np.integer)) or max_frames < 1:
        raise ValueError(f"max_frames must be a positive integer, got {max_frames!r}")
    N = labels.shape[0]
    if N <= max_frames:
        return np.arange(N, dtype=np.int64)
    sizes = np.bincount(labels)
    quota = np.maximum(1, (int(max_frames) * sizes) // N)
    order = np.random.default_rng(random_state).permutation(N)
    lab = labels[order]
    by_state = np.argsort(lab, kind="stable")  # frames of each state, in random order
    state_of = lab[by_state]  # the state of each of them (sorted)
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    rank = np.arange(N) - starts[state_of]  # position of each frame within its state
    keep = order[by_state[rank < quota[state_of]]]
    keep.sort()
    return keep.astype(np.int64)


def cloud_frames(labels, *, max_frames: int | None = None):
    """:func:`cloud_subsample`'s frames, or None when every frame is drawn (what the scene takes).

    ``max_frames`` None: :data:`DEFAULT_MAX_FRAMES`, read when called.
    """
    labels = np.asarray(labels)
    max_frames = DEFAULT_MAX_FRAMES if max_frames is None else max_frames
    return None if labels.shape[0] <= max_frames else cloud_subsample(labels, max_frames=max_frames)

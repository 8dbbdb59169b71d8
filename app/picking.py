"""From a click in a 3-D view to a frame index: pure functions, then the state.

The VTK callback only hands a picked point (xyz) or a point id to
:func:`pick_to_frame`, and the result to :meth:`app.state.AppState.select_frame`,
so each layer is tested on its own.
"""
from __future__ import annotations

import numpy as np

__all__ = ["pick_to_frame", "PointLocator", "handle_pick", "hover_text"]


def pick_to_frame(picked, Fy3) -> int:
    """The frame whose F^y point is nearest to the picked point.

    Parameters
    ----------
    picked : sequence of 3 floats, or int
        The picked position in the view's coordinates, or a point id of the
        manifold's point cloud (returned as is after a range check).
    Fy3 : ndarray of shape (N, 3)
        The drawn points (the first three dims of F^y).

    Returns
    -------
    int
    """
    Fy3 = np.asarray(Fy3)
    if Fy3.ndim != 2 or Fy3.shape[1] != 3 or Fy3.shape[0] == 0:
        raise ValueError(f"Fy3 must have shape (N, 3) with N > 0, got {Fy3.shape}")
    if isinstance(picked, (int, np.integer)) and not isinstance(picked, (bool, np.bool_)):
        i = int(picked)
        if not 0 <= i < Fy3.shape[0]:
            raise IndexError(f"picked point id {i} out of range 0..{Fy3.shape[0] - 1}")
        return i
    p = np.asarray(picked, dtype=np.float64).reshape(-1)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"picked point must be 3 finite coordinates or a point id, got {picked!r}")
    d = ((Fy3.astype(np.float64) - p) ** 2).sum(axis=1)
    return int(np.argmin(d))


class PointLocator:
    """Nearest-frame look-up with a KD-tree built once (for large manifolds)."""

    def __init__(self, Fy3):
        from scipy.spatial import cKDTree

        self.Fy3 = np.asarray(Fy3, dtype=np.float64)
        if self.Fy3.ndim != 2 or self.Fy3.shape[1] != 3 or self.Fy3.shape[0] == 0:
            raise ValueError(f"Fy3 must have shape (N, 3) with N > 0, got {self.Fy3.shape}")
        self._tree = cKDTree(self.Fy3)

    def __call__(self, picked) -> int:
        if isinstance(picked, (int, np.integer)) and not isinstance(picked, (bool, np.bool_)):
            return pick_to_frame(picked, self.Fy3)
        p = np.asarray(picked, dtype=np.float64).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"picked point must be 3 finite coordinates or a point id, got {picked!r}")
        return int(self._tree.query(p)[1])


def handle_pick(state, picked, locator, *, as_target: bool | None = None) -> int:
    """Select the frame nearest ``picked`` in ``state``; returns the frame index.

    ``as_target`` True makes its state the path target (a shift-click or the path
    toggle); None lets :attr:`AppState.path_mode` decide.
    """
    i = locator(picked)
    state.select_frame(i, as_target=as_target)
    return i


def hover_text(manifold, phones, i) -> str:
    """The readout of frame ``i`` under the pointer: frame, utterance, time, phone, state, tangent class."""
    from app.colouring import CLASS_LABELS

    c = manifold.corpus_
    u = c.utterances[int(c.utterance_index[i])]
    cls = int(manifold.tangent_.classes_[i])
    return (f"frame {i} ({u.id}, t={(i - u.start) / c.rate:.3f} s) · phone {phones[i] or '—'} · "
            f"state {int(manifold.states_.labels_[i])} · {CLASS_LABELS[cls] if cls >= 0 else 'no step'}")

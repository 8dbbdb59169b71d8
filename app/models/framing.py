"""What "frame the selection" brings into view: the box around the chosen clusters and the selection (Qt-free)."""
from __future__ import annotations

import numpy as np

__all__ = ["selection_bounds", "FRAME_NEIGHBOURHOOD"]

#: a single selected point is framed with this share of the cloud's extent around it (its neighbourhood)
FRAME_NEIGHBOURHOOD = 0.15


def selection_bounds(state, *, neighbourhood: float = FRAME_NEIGHBOURHOOD):
    """The box ``(lo (3,), hi (3,))`` in F^y's first three dimensions that holds what is chosen, or None.

    What is chosen: the shown cluster ellipsoids (whole), the selected frame (or the selected
    state's centroid), the target and the path between them; with none of these, the
    trajectories shown. A box thinner than ``neighbourhood`` times the cloud's largest
    extent is widened to it around its centre, so one point is framed with its neighbours.
    None when nothing is chosen (the view then shows the whole cloud).
    """
    m = state.manifold
    if m is None:
        return None
    parts = []
    for label in sorted(state.visible_phones):
        verts, _faces = state.clusters.ellipsoid(label)
        parts.append(np.asarray(verts, np.float64)[:, :3])
    C = m.states_.centroids_
    if state.frame is not None:
        parts.append(np.asarray(m.Fy_[state.frame, :3], np.float64)[None])
    elif state.state is not None:
        parts.append(np.asarray(C[state.state, :3], np.float64)[None])
    if state.target is not None:
        parts.append(np.asarray(C[state.target, :3], np.float64)[None])
    if state.path is not None:
        parts.append(np.asarray(C[np.asarray(state.path), :3], np.float64))
    if not parts:
        parts = [np.asarray(t.Y, np.float64)[:, :3] for t in (state.original, state.synthetic) if t is not None]
    if not parts:
        return None
    P = np.vstack(parts)
    lo, hi = P.min(axis=0), P.max(axis=0)
    b = np.asarray(state.cloud.bounds, np.float64)  # (2, 3): lowest and highest corner of the cloud
    least = neighbourhood * float(np.max(b[1] - b[0]))
    centre = 0.5 * (lo + hi)
    half = np.maximum(0.5 * (hi - lo), 0.5 * least)
    return centre - half, centre + half

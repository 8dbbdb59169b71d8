"""Clicked states as a path and as synthesis targets: the explorer's fewest-hop path and the inserted target."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["state_path", "insert_state_target", "TARGET_SPACING"]

#: seconds between an appended clicked-state target and the last target (as ``synthesize --spacing``)
TARGET_SPACING = 0.2


def state_path(manifold, a: int, b: int):
    """Minimum-distance state path a -> b (ndarray of int), or None when b is unreachable."""
    from engine.graph.states import UnreachableError

    try:
        return np.asarray(manifold.states_.min_path(int(a), int(b)), dtype=np.int64)
    except UnreachableError:
        return None


def insert_state_target(manifold, targets, state: int, *, frame=None, spacing: float = TARGET_SPACING):
    """A copy of ``targets`` (a TargetSequence, or None) with a target holding ``state`` inserted.

    The target goes at ``frame`` (replacing a target already there), or, with
    ``frame=None``, ``spacing`` seconds after the last target (frame 0 when there are
    none). The trajectory is lengthened to reach the new target. The target carries the
    state (which :class:`engine.synthesis.viterbi.ViterbiSynthesizer` passes through) and the
    state's X (the manifold's map of its centroid, ``state_x_``, else the mean F^x of its
    frames), so the methods that interpolate in X pass through it too. Its label is "".
    """
    from engine.phonetics.targets import Target, TargetError, TargetSequence

    K = int(manifold.states_.centroids_.shape[0])
    s = int(state)
    if not 0 <= s < K:
        raise TargetError(f"state {s} is outside the state graph's 0..{K - 1}")
    rate = float(targets.rate if targets is not None else manifold.corpus_.rate)
    old = list(targets.targets) if targets is not None else []
    if frame is None:
        frame = old[-1].frame + max(1, int(round(spacing * rate))) if old else 0
    frame = int(frame)
    if frame < 0:
        raise TargetError(f"target frame {frame} is negative")
    table = getattr(manifold, "state_x_", None)  # (not computed here: a click must not wait for it)
    if table is not None and table.shape[0] == K:
        x = np.asarray(table[s], dtype=np.float64)
    else:
        x = np.asarray(manifold.Fx_)[np.asarray(manifold.states_.labels_) == s].mean(axis=0, dtype=np.float64)
    new = Target(frame, "", s, None, x)
    ts = sorted([t for t in old if t.frame != frame] + [new], key=lambda t: t.frame)
    n = max(targets.n_frames if targets is not None else 1, frame + 1)
    if targets is None:
        return TargetSequence(tuple(ts), (), n, rate, "clicked states")
    return replace(targets, targets=tuple(ts), n_frames=n)

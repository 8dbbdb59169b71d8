"""Level of detail of the manifold cloud: one drawn point per group of frames, coloured from all of them.

A corpus of a million frames is more than a 3-D view redraws interactively, and more
than the eye separates. Up to ``max_points`` frames (:data:`DEFAULT_MAX_POINTS`) every
frame is drawn and is its own group. Above, the frames are grouped by **state and by a
cell of a regular grid over Y1-3**, the cell's edge chosen so that at most
``max_points`` groups form (:func:`cloud_detail`). Each group is drawn as one point, at
its member nearest the members' mean (a real frame), and every colour the view gives it
is computed from all its members (:mod:`app.models.colouring`):

* what is constant over a state (hop distance, the selected state) is the state's: a
  group never spans two states, so hemisphere colours are exactly those of its frames;
* density: the frames in the group's grid cell (every state's) over N times the cell's
  volume (:attr:`CloudDetail.density`), a histogram estimate from every frame;
* categories (tangent class, phone, utterance): the most frequent among the members
  (:meth:`CloudDetail.plurality`).

Picking and hover search the members of the groups near the cursor, so they find a
frame of the full data, not a group's drawn point (:class:`app.models.picking.CloudLocator`).
Selections stay frame indices.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CloudDetail", "cloud_detail", "DEFAULT_MAX_POINTS"]

#: points drawn at most (every frame up to this many)
DEFAULT_MAX_POINTS = 40_000
#: the grid search stops once the groups number at least this share of ``max_points``
_FILL = 0.85
#: grid-cell evaluations of the search at most (on the sample, then on every frame)
_MAX_STEPS = 12
#: frames of the sample the search starts on (above twice as many frames)
_SAMPLE = 400_000


@dataclass(frozen=True, eq=False)
class CloudDetail:
    """Which frames the manifold view draws and which frames each drawn point stands for.

    Attributes
    ----------
    frames : ndarray of shape (G,), int64
        The frame drawn for each group (its member nearest the members' mean).
    order : ndarray of shape (N,), int64
        Every frame, sorted by group (ascending frame index within a group).
    offsets : ndarray of shape (G + 1,), int64
        Group g's members are ``order[offsets[g]:offsets[g + 1]]``.
    group_of : ndarray of shape (N,), int64
        The group of each frame.
    state : ndarray of shape (G,), int64
        The state of each group's frames (one state per group).
    radius : ndarray of shape (G,), float64
        The largest distance in Y1-3 of a member from the drawn frame (0 for one frame).
    cell : float or None
        Edge of the grid cells (None: every frame is its own group).
    density : ndarray of shape (G,), float32, or None
        Log histogram density of each group's cell: ``log(n_cell / (N * cell**3))``,
        n_cell the frames of every state in the cell (None when every frame is drawn:
        the view uses the frames' k-NN density then).
    bounds : ndarray of shape (2, 3)
        Smallest and largest Y1-3 over every frame.
    """

    frames: np.ndarray
    order: np.ndarray
    offsets: np.ndarray
    group_of: np.ndarray
    state: np.ndarray
    radius: np.ndarray
    cell: float | None
    density: np.ndarray | None
    bounds: np.ndarray

    @property
    def n_frames(self) -> int:
        return int(self.order.shape[0])

    @property
    def n_points(self) -> int:
        """G, the drawn points."""
        return int(self.frames.shape[0])

    @property
    def whole(self) -> bool:
        """Whether every frame is drawn (point i is frame i)."""
        return self.cell is None

    @property
    def sizes(self) -> np.ndarray:
        """(G,) int64: frames per group."""
        return np.diff(self.offsets)

    def members(self, groups) -> np.ndarray:
        """The frames of ``groups`` (int or int array), in group order."""
        g = np.atleast_1d(np.asarray(groups, dtype=np.int64))
        if g.size == 0:
            return np.zeros(0, np.int64)
        a, b = self.offsets[g], self.offsets[g + 1]
        n = b - a
        # positions a_j .. b_j - 1 of every group, without a Python loop
        pos = np.repeat(a - np.concatenate([[0], np.cumsum(n)[:-1]]), n) + np.arange(int(n.sum()))
        return self.order[pos]

    def groups_of(self, frames) -> np.ndarray:
        """The distinct groups holding ``frames`` (sorted)."""
        return np.unique(self.group_of[np.asarray(frames, dtype=np.int64)])

    def any_of(self, mask) -> np.ndarray:
        """(G,) bool: groups with at least one frame where ``mask`` (N,) is True."""
        mask = np.asarray(mask, dtype=bool)
        return np.bincount(self.group_of[mask], minlength=self.n_points) > 0

    def plurality(self, codes, n_codes: int) -> np.ndarray:
        """(G,) int64: each group's most frequent code (the smallest on a tie).

        Parameters
        ----------
        codes : ndarray of shape (N,), int in 0..n_codes-1
        n_codes : int
        """
        codes = np.asarray(codes, dtype=np.int64)
        G, n = self.n_points, int(n_codes)
        if self.whole:
            return codes.copy()
        if G * n <= 2**25:  # a dense count table is small enough
            counts = np.bincount(self.group_of * n + codes, minlength=G * n).reshape(G, n)
            return counts.argmax(axis=1)
        keys, counts = np.unique(self.group_of * n + codes, return_counts=True)
        g, c = keys // n, keys % n
        best = np.lexsort((c, -counts, g))  # per group: the highest count, then the smallest code
        first = best[np.r_[True, g[best][1:] != g[best][:-1]]]
        out = np.zeros(G, np.int64)
        out[g[first]] = c[first]
        return out


def _whole(Y, labels) -> CloudDetail:
    N = Y.shape[0]
    idx = np.arange(N, dtype=np.int64)
    return CloudDetail(idx, idx, np.arange(N + 1, dtype=np.int64), idx, labels.copy(), np.zeros(N), None, None,
                       np.array([Y.min(0), Y.max(0)]) if N else np.zeros((2, 3)))


def _cells(Y, lo, hi, h):
    """Grid cell of every frame: (N,) int64 cell number, and the cells per axis (float64 arithmetic)."""
    n = np.floor((hi - lo) / h).astype(np.int64) + 1  # the largest index is the top corner's (same arithmetic)
    cell = np.zeros(Y.shape[0], np.int64)
    for c in range(3):  # a column at a time: no (N, 3) temporaries
        cell *= n[c]
        cell += np.floor((Y[:, c].astype(np.float64) - lo[c]) / h).astype(np.int64)
    return cell, n


def _keys(Y, labels, lo, hi, h, n_states) -> np.ndarray:
    """(N,) int64: one number per (state, cell) pair."""
    cell, n = _cells(Y, lo, hi, h)
    cells = int(np.prod([int(x) for x in n]))
    if cells * n_states < 2**62:
        return labels * cells + cell
    _u, inv = np.unique(cell, return_inverse=True)  # renumber the occupied cells only
    return labels * (int(inv.max()) + 1) + inv.reshape(-1)


def _count(keys) -> int:
    s = np.sort(keys)
    return 1 + int(np.count_nonzero(s[1:] != s[:-1]))


def _grouped(Y, labels, lo, hi, h, n_states):
    """Every frame sorted by (state, cell) group, then frame: (order (N,), first (N,) bool: a group starts here)."""
    N = Y.shape[0]
    key = _keys(Y, labels, lo, hi, h, n_states)
    if int(key.max()) >= 2**62 // N:  # renumber the (state, cell) pairs so that key * N fits in int64
        key = np.unique(key, return_inverse=True)[1].reshape(-1)
    both = np.sort(key * N + np.arange(N, dtype=np.int64))  # by group, then frame: one sort of N numbers
    del key
    ks = both // N
    first = np.r_[True, ks[1:] != ks[:-1]]
    del ks
    both %= N
    return both, first


def cloud_detail(Y, labels, *, max_points: int | None = None) -> CloudDetail:
    """Group the frames for drawing: every frame while N <= ``max_points``, else by state and grid cell.

    Parameters
    ----------
    Y : ndarray of shape (N, >=3)
        F^y (only Y1-3 are used).
    labels : ndarray of shape (N,), int
        State of each frame (``StateGraph.labels_``), values in 0..K-1.
    max_points : int, optional
        Points drawn at most (default :data:`DEFAULT_MAX_POINTS`, read when called). Above
        it the grid's cell edge is searched (a few sorts of N keys) for between
        ``0.85 * max_points`` and ``max_points`` groups; with K >= max_points states a
        group is a whole state.

    Returns
    -------
    CloudDetail
    """
    max_points = DEFAULT_MAX_POINTS if max_points is None else max_points
    if isinstance(max_points, bool) or not isinstance(max_points, (int, np.integer)) or max_points < 1:
        raise ValueError(f"max_points must be a positive integer, got {max_points!r}")
    labels = np.asarray(labels)
    if labels.ndim != 1 or (labels.size and (not np.issubdtype(labels.dtype, np.integer) or labels.min() < 0)):
        raise ValueError(f"labels must be a 1-D array of state indices >= 0, got dtype {labels.dtype}, "
                         f"shape {labels.shape}")
    Y = np.asarray(Y)
    if Y.ndim != 2 or Y.shape[1] < 3 or Y.shape[0] != labels.shape[0]:
        raise ValueError(f"Y must have shape (N, >=3) with N = {labels.shape[0]} (one row per label), got {Y.shape}")
    labels = labels.astype(np.int64)
    N = Y.shape[0]
    # Y1-3 in their own precision (F^y is float32: 12 bytes a frame); cells are found in float64
    Y = np.ascontiguousarray(Y[:, :3], dtype=np.float64 if Y.dtype.itemsize > 4 else np.float32)
    if not np.isfinite(Y).all():
        raise ValueError("Y holds NaN or infinite values; a fitted manifold never does")
    if N <= max_points:
        return _whole(Y.astype(np.float64), labels)
    lo, hi = Y.min(axis=0).astype(np.float64), Y.max(axis=0).astype(np.float64)
    extent = np.maximum(hi - lo, 0.0)
    big = float(extent.max()) * 2.0 + 1.0  # one cell holds everything
    K = int(labels.max()) + 1
    h_min = float(extent.max()) * 2.0**-40 + 1e-300  # cell numbers stay far inside int64
    # search the edge: groups fall as the cells grow (G ~ h^-a); secant steps in log-log, first on a
    # random sample of the frames (each step sorts its keys), then on every frame from there
    kept: dict = {}  # on every frame: the grouping of the finest grid within the cap so far, used as is
    target = 0.5 * (_FILL + 1.0) * max_points

    def on_sample(Ys, ls):
        return lambda h: _count(_keys(Ys, ls, lo, hi, h, K))

    def on_every_frame(h):
        order, first = _grouped(Y, labels, lo, hi, h, K)
        g = int(np.count_nonzero(first))
        if g <= max_points and (not kept or h < kept["h"]):
            kept.update(h=h, order=order, first=first)
        return g

    def search(count, h, slope, steps):
        memo = {}

        def groups(h):
            h = float(min(max(h, h_min), big))
            if h not in memo:
                memo[h] = count(h)
            return h, memo[h]

        h, g = groups(h)
        for _ in range(steps):
            if _FILL * max_points <= g <= max_points or h >= big:
                break
            h_new, g_new = groups(h * (g / target) ** (1.0 / slope))
            if h_new == h:
                break
            if g_new != g:
                slope = float(np.clip(-np.log(g_new / g) / np.log(h_new / h), 0.5, 6.0))
            h, g = h_new, g_new
        return h, slope

    flat = np.maximum(extent, extent.max() * 1e-3)
    h = max(float(np.prod(flat)) / max_points, 1e-300) ** (1 / 3)
    slope = 2.5
    if N > 2 * _SAMPLE:
        pick = np.random.default_rng(0).choice(N, _SAMPLE, replace=False)
        h, slope = search(on_sample(Y[pick], labels[pick]), h, slope, _MAX_STEPS)
    search(on_every_frame, h, slope, _MAX_STEPS)
    if kept:  # the finest grid within the cap
        h, order, first = kept["h"], kept["order"], kept["first"]
    else:  # none within it: whole states (K groups)
        h = big
        order, first = _grouped(Y, labels, lo, hi, h, K)
    starts = np.flatnonzero(first)
    offsets = np.r_[starts, N].astype(np.int64)
    sizes = np.diff(offsets)
    group_of = np.empty(N, np.int64)
    group_of[order] = np.cumsum(first) - 1
    gs = group_of[order]
    Yo = Y[order]
    mean = (np.add.reduceat(Yo, starts, axis=0, dtype=np.float64) / sizes[:, None]).astype(Yo.dtype)
    d2 = ((Yo - mean[gs]) ** 2).sum(axis=1)
    near = np.flatnonzero(d2 == np.minimum.reduceat(d2, starts)[gs])
    near = near[np.r_[True, gs[near][1:] != gs[near][:-1]]]  # the first nearest member per group
    frames = order[near]
    r2 = np.maximum.reduceat(((Yo - Y[frames][gs]) ** 2).sum(axis=1), starts).astype(np.float64)
    # the farthest member, computed in Y's precision: a hair larger, so that it bounds the float64 distance
    radius = np.sqrt(r2) * (1 + 1e-5) + 1e-7 * float((hi - lo).max())
    del Yo, d2, gs
    cell, _n = _cells(Y[frames], lo, hi, h)
    uc, inv = np.unique(cell, return_inverse=True)
    in_cell = np.bincount(inv.reshape(-1), weights=sizes, minlength=uc.size)[inv.reshape(-1)]
    density = (np.log(in_cell) - np.log(N) - 3.0 * np.log(h)).astype(np.float32)
    return CloudDetail(frames.astype(np.int64), order.astype(np.int64), offsets, group_of.astype(np.int64),
                       labels[frames], radius, float(h), density, np.array([lo, hi]))

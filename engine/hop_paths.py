"""Fewest-hop paths between two states of a directed graph, by a bidirectional breadth-first search.

The explorer's state path (:meth:`engine.states.StateGraph.min_path`) is a path of
fewest hops (one hop ~ one frame) from the selected state to the target state. A
breadth-first search from the first state finds it, but visits every state it can
reach: at K = 20,000 states (525,000 edges) that is the whole graph for every query,
though the median pair is only 5 hops apart. Here the search grows two balls instead,
forward from ``a`` over A and backward from ``b`` over A^T, always expanding the
side whose frontier has fewer edges to follow, and stops when they meet: at
K = 20,000 the two balls hold a few thousand states instead of all of them.

Which path among several of fewest hops? The one a breadth-first search from ``a``
with sorted rows would give (its predecessor tree, as
``scipy.sparse.csgraph.breadth_first_order``): that tree path is the
lexicographically smallest sequence of states among all fewest-hop paths (each
state's tree parent is the first parent in queue order, and queue order is the
lexicographic order of tree paths). It is rebuilt greedily from ``a``: at each hop
the smallest next state that still lies on a fewest-hop path to ``b``. So the result
is exactly the path of the full search, found from the two balls only.

Pure numpy; every step is a vectorised gather over the rows of the current frontier.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["fewest_hop_path", "concat_ranges", "mark_level"]


def concat_ranges(lo, n) -> np.ndarray:
    """``concatenate([arange(lo[i], lo[i] + n[i]) for i ...])`` without a Python loop (int64)."""
    total = int(n.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    return np.arange(total) + np.repeat(lo - (np.cumsum(n) - n), n)


def _rows(G: sp.csr_matrix, nodes: np.ndarray) -> np.ndarray:
    """Column indices of the rows ``nodes`` of csr ``G``, concatenated in row order."""
    lo = G.indptr[nodes]
    return G.indices[concat_ranges(lo, G.indptr[nodes + 1] - lo)]


def mark_level(reached, dist, level) -> np.ndarray:
    """The nodes of ``reached`` with ``dist < 0`` (not yet reached), marked ``level`` in
    ``dist`` (in place): the next breadth-first frontier, sorted, without repeats."""
    new = reached[dist[reached] < 0]
    if new.size == 0:
        return new
    dist[new] = level
    if new.size * 16 < dist.size:
        return np.unique(new)
    return np.flatnonzero(dist == level)


def _grow(G, frontier, dist, level):
    """One breadth-first level over csr ``G`` from ``frontier`` (see :func:`mark_level`)."""
    return mark_level(_rows(G, frontier), dist, level)


def fewest_hop_path(G, GT, a: int, b: int):
    """A fewest-hop path from ``a`` to ``b`` over the directed graph ``G``.

    Parameters
    ----------
    G : scipy.sparse.csr_matrix of shape (K, K)
        Edges ``i -> j`` where ``G[i, j]`` is stored, with sorted indices (ties are
        broken by the order of each row).
    GT : scipy.sparse.csr_matrix of shape (K, K)
        ``G`` transposed (csr), the edges reversed.
    a, b : int
        First and last node, in 0..K-1.

    Returns
    -------
    ndarray of shape (hops + 1,), int64 or None
        Nodes from ``a`` to ``b`` inclusive, consecutive ones joined by an edge of
        ``G``; ``[a]`` when ``a == b``; None when ``b`` cannot be reached from ``a``.
        Among several fewest-hop paths, the path of the predecessor tree of a
        breadth-first search from ``a`` (the lexicographically smallest sequence).
    """
    a, b = int(a), int(b)
    K = G.shape[0]
    for name, s in (("a", a), ("b", b)):
        if not 0 <= s < K:
            raise ValueError(f"{name}={s} is out of range: the graph has {K} nodes (0..{K - 1})")
    if a == b:
        return np.array([a], dtype=np.int64)
    if not G.has_sorted_indices:
        raise ValueError("the graph's rows must have sorted indices (call G.sort_indices() once)")
    da = np.full(K, -1, dtype=np.int32)  # hops from a (forward ball)
    db = np.full(K, -1, dtype=np.int32)  # hops to b (backward ball)
    da[a], db[b] = 0, 0
    fa, fb = np.array([a]), np.array([b])
    ka = kb = 0
    while True:
        # grow the ball whose frontier has fewer edges to follow
        if G.indptr[fa + 1].sum() - G.indptr[fa].sum() <= GT.indptr[fb + 1].sum() - GT.indptr[fb].sum():
            ka += 1
            fa = _grow(G, fa, da, ka)
            if fa.size == 0:
                return None
            meet = fa[db[fa] >= 0]
        else:
            kb += 1
            fb = _grow(GT, fb, db, kb)
            if fb.size == 0:
                return None
            meet = fb[da[fb] >= 0]
        if meet.size:
            break
    # Before this level the two balls were disjoint, so no path is shorter than
    # ka + kb hops, and the states where they meet lie ka hops from a and kb from b.
    d = ka + kb
    # States of the forward ball on a fewest-hop path: the meeting states (level ka),
    # then level by level those with an edge into the level above that are on one.
    on = np.zeros(K, dtype=bool)
    good = meet[da[meet] == ka]
    on[good] = True
    for j in range(ka - 1, -1, -1):
        prev = _rows(GT, good)
        good = prev[da[prev] == j]
        on[good] = True
    path = np.empty(d + 1, dtype=np.int64)
    path[0] = x = a
    ind, ptr = G.indices, G.indptr
    for i in range(d):
        row = ind[ptr[x]:ptr[x + 1]]
        if i + 1 <= ka:  # next state inside the forward ball: on a fewest-hop path, one hop further
            ok = on[row] & (da[row] == i + 1)
        else:  # inside the backward ball: one hop nearer b (then necessarily on a fewest-hop path)
            ok = db[row] == d - i - 1
        x = int(row[int(np.argmax(ok))])
        path[i + 1] = x
    return path

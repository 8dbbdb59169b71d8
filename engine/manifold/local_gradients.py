"""Local gradient fields over the embedding F^y, fitted from the movements through each neighbourhood.

A quantity f measured per frame (the lip aperture, its velocity) is a function on the
manifold. Its local gradient g_i at frame i is what the tangent frames need: the step
z_i of the trajectory through frame i changes f by about z_i . g_i. The gradient is
fitted to the **steps** of the frames near y_i, not to the values of f there::

    g_i = argmin_g  sum_j w_ij (z_j . g - df_j)^2 + ridge |g|^2,   j in the k nearest
    frames of y_i in F^y (i itself included),

where z_j is frame j's central step in F^y and df_j the central difference of f at
j. Matching increments instead of values cancels what a plane through the values
gets wrong on a curved manifold (neighbours far along the surface), and it needs no
intercept: no step, no change. The weights are Gaussian in the distance to y_i, with
the spread set to half the distance of the k-th neighbour.

**The neighbourhood size k is chosen per corpus** by :func:`select_neighbors`: the
corpus's frames are split into folds (whole utterances, or contiguous blocks of the
utterances when there are fewer than five), each fold's gradients are fitted from
the other folds only (frames closer in time than :data:`MARGIN_S` to a held-out frame
are left out too), and the k whose held-out steps predict the sign of the measured
changes best wins. The candidates are set by the size of the corpus and of F^y
(:func:`neighbor_candidates`), the margin by its frame rate; nothing is fixed in
advance for a particular corpus.

Above :data:`MAX_ANCHORS` frames the gradients are fitted at that many frames spread
at random over the corpus (the *anchors*) and every frame takes the gradients of its
nearest anchor, so the cost stops growing with k times N.
"""
from __future__ import annotations

import numpy as np

__all__ = ["central_difference", "neighbor_candidates", "local_gradients", "gradients_block",
           "select_neighbors", "MAX_NEIGHBORS", "MAX_ANCHORS", "MARGIN_S", "N_FOLDS"]

#: the largest neighbourhood considered
MAX_NEIGHBORS = 352
#: frames above which the gradients are fitted at this many anchors only
MAX_ANCHORS = 5000
#: frames closer in time than this (seconds) to a held-out frame are left out of its fit
MARGIN_S = 0.05
#: folds of the neighbourhood validation
N_FOLDS = 5
#: held-out frames scored per fold at most
_QUERIES_PER_FOLD = 500
#: ridge of the regressions, relative to the weighted steps' mean square per dimension
_RIDGE = 1e-3
#: rows per block of the batched solves
_BLOCK = 512


def central_difference(x, bounds) -> np.ndarray:
    """Central difference per frame inside each utterance (one-sided at its ends).

    Parameters
    ----------
    x : ndarray of shape (N,) or (N, d)
    bounds : int ndarray of shape (U, 2)
        Utterance ``[start, stop)`` ranges.

    Returns
    -------
    ndarray of the shape of ``x``, float64
        ``(x[i+1] - x[i-1]) / 2`` inside an utterance, ``x[1] - x[0]`` and
        ``x[-1] - x[-2]`` at its ends, 0 in an utterance of one frame.
    """
    x = np.asarray(x, dtype=np.float64)
    out = np.zeros_like(x)
    for s, e in np.asarray(bounds, dtype=np.int64):
        if e - s >= 2:
            out[s:e] = np.gradient(x[s:e], axis=0)
    return out


def neighbor_candidates(n_frames: int, n_dims: int) -> tuple[int, ...]:
    """Neighbourhood sizes worth validating for ``n_frames`` frames in ``n_dims`` dims.

    From ``2 (n_dims + 1)`` (twice the unknowns of a gradient with an offset) doubling,
    while a fold's fit still has twice the neighbours it asks for and up to
    :data:`MAX_NEIGHBORS`; at least the smallest one.
    """
    k = 2 * (int(n_dims) + 1)
    cap = min(MAX_NEIGHBORS, int(0.5 * (1 - 1 / N_FOLDS) * n_frames))
    out = [min(k, max(3, int(n_frames) - 2))]
    while 2 * k <= cap:
        k *= 2
        out.append(k)
    return tuple(out)


def _weights(dist):
    """Gaussian weights (B, k) from neighbour distances (B, k): spread half the k-th distance."""
    h = 0.5 * dist[:, -1:]
    h = np.where(h > 0, h, 1.0)
    return np.exp(-0.5 * (dist / h) ** 2)


def _solve(Zk, Fk, w):
    """Weighted ridge gradients (B, T, d) from neighbour steps Zk (B, k, d) and changes Fk (B, k, T).

    The weighted sums run in float32 (the steps are float32); the d x d systems in float64.
    """
    d = Zk.shape[2]
    ZwT = (Zk * w[..., None].astype(np.float32)).transpose(0, 2, 1)  # (B, d, k)
    C = (ZwT @ Zk).astype(np.float64)
    lam = _RIDGE * np.trace(C, axis1=1, axis2=2) / d + 1e-300
    C[:, np.arange(d), np.arange(d)] += lam[:, None]
    R = (ZwT @ Fk.astype(np.float32)).astype(np.float64)
    return np.linalg.solve(C, R).transpose(0, 2, 1)


def _query(tree, X, k):
    """(distances, indices) of the ``k`` nearest points of ``tree`` to each row of X, nearest first."""
    dist, idx = tree.query(X, k=k, workers=-1)
    if k == 1:
        dist, idx = dist[:, None], idx[:, None]
    return dist, idx


def gradients_block(start, stop, tree, Y, Z, F, k, anchors):
    """Gradients at anchors ``start:stop`` (see the module notes).

    Parameters
    ----------
    start, stop : int
        A block of ``anchors``.
    tree : scipy.spatial.cKDTree
        Of all of Y.
    Y, Z : ndarray of shape (N, d)
        Positions and central steps of the frames.
    F : ndarray of shape (N, T)
        Central differences of the T quantities.
    k : int
        Neighbours (the anchor itself included).
    anchors : int ndarray of shape (M,)
        Frames at which gradients are fitted.

    Returns
    -------
    ndarray of shape (stop - start, T, d), float32
    """
    out = []
    for a in range(start, stop, _BLOCK):
        rows = anchors[a:min(stop, a + _BLOCK)]
        dist, idx = _query(tree, Y[rows], k)
        out.append(_solve(Z[idx], F[idx], _weights(dist)).astype(np.float32))
    return np.concatenate(out) if out else np.zeros((0, F.shape[1], Y.shape[1]), np.float32)


def local_gradients(Y, Z, F, k, *, executor=None, random_state=0):
    """Local gradients of every quantity at every frame.

    Parameters
    ----------
    Y : ndarray of shape (N, d)
        Frames in F^y.
    Z : ndarray of shape (N, d)
        Their central steps (:func:`central_difference` of Y).
    F : ndarray of shape (N, T)
        Central differences of T quantities per frame.
    k : int
        Neighbourhood size (the frame itself included).
    executor : object with ``map_row_blocks``, optional
        Fits blocks of anchors as separate tasks (:meth:`engine.scale.executor.DaskExecutor.map_row_blocks`).
    random_state : int
        Seed of the anchors' choice above :data:`MAX_ANCHORS` frames.

    Returns
    -------
    G : ndarray of shape (N, T, d), float32
    n_anchors : int
        Frames the gradients were fitted at (N up to :data:`MAX_ANCHORS`).
    """
    from scipy.spatial import cKDTree  # on use: loading a fitted manifold needs none of SciPy's spatial package

    N = Y.shape[0]
    Y = np.ascontiguousarray(Y, dtype=np.float32)
    k = int(min(k, N))
    tree = cKDTree(Y)
    if N <= MAX_ANCHORS:
        anchors = np.arange(N)
    else:
        anchors = np.sort(np.random.default_rng(random_state).choice(N, MAX_ANCHORS, replace=False))
    M = len(anchors)
    if executor is None:
        G = gradients_block(0, M, tree, Y, Z, F, k, anchors)
    else:
        G = np.concatenate(executor.map_row_blocks(gradients_block, M, tree, Y, Z, F, k, anchors, block=4 * _BLOCK))
    if M == N:
        return G, M
    near = _query(cKDTree(Y[anchors]), Y, 1)[1][:, 0]
    return G[near], M


def _folds(bounds, n_folds):
    """Fold of every frame: utterances in turn, or contiguous blocks of each utterance."""
    b = np.asarray(bounds, dtype=np.int64)
    f = np.empty(int(b[-1, 1]), np.int64)
    if len(b) >= n_folds:
        for u, (s, e) in enumerate(b):
            f[s:e] = u % n_folds
    else:
        for s, e in b:
            edges = np.linspace(s, e, n_folds + 1).round().astype(np.int64)
            for j in range(n_folds):
                f[edges[j]:edges[j + 1]] = j
    return f


def _agreement(pred, truth):
    """Sign agreement weighted by |truth| (frames of no change count nothing)."""
    w = np.abs(truth)
    return float(np.sum(w * ((pred > 0) == (truth > 0))) / w.sum()) if w.sum() > 0 else float("nan")


def select_neighbors(Y, Z, F, bounds, rate, *, candidates, dims=None, random_state=0):
    """Choose the neighbourhood (its size, and the dims of F^y) by held-out prediction of the opening and its speed.

    Parameters
    ----------
    Y, Z : ndarray of shape (N, d)
        Frames in F^y and their central steps.
    F : ndarray of shape (N, 2)
        Central differences of the opening (column 0) and of its velocity (column 1).
    bounds : int ndarray of shape (U, 2)
    rate : float
        Frames per second (sets the time margin around held-out frames).
    candidates : sequence of int or callable
        Neighbourhood sizes to compare, or a function of the dims giving them.
    dims : sequence of int, optional
        Leading dims of F^y to compare (default: all d).
    random_state : int
        Seed of the held-out frames scored when a fold has more than can be scored.

    Returns
    -------
    dims, k : int
        The candidate with the highest sum of the two held-out agreements (the
        fewer dims and the smaller k on a tie).
    scores : ndarray of shape (n_candidates, 4)
        ``[dims, k, opening agreement, acceleration agreement]`` per candidate: how
        often, weighted by the size of the measured change, the sign of the held-out
        frames' predicted opening change, and of their speed change, was right.
    """
    dims = sorted({int(d) for d in (dims or (Y.shape[1],))})
    rows = []
    for d in dims:
        ks = candidates(d) if callable(candidates) else candidates
        for k, so, sa in _validate(Y[:, :d], Z[:, :d], F, bounds, rate, sorted(int(k) for k in ks), random_state):
            rows.append((d, k, so, sa))
    scores = np.array(rows, dtype=np.float64)
    total = np.nan_to_num(scores[:, 2]) + np.nan_to_num(scores[:, 3])
    best = int(np.argmax(total))
    return int(scores[best, 0]), int(scores[best, 1]), scores


def _validate(Y, Z, F, bounds, rate, candidates, random_state):
    """``[(k, opening, acceleration)]``: held-out agreements per candidate k (see :func:`select_neighbors`)."""
    from scipy.spatial import cKDTree

    N = Y.shape[0]
    Y = np.ascontiguousarray(Y, dtype=np.float32)
    fold = _folds(bounds, N_FOLDS)
    margin = max(1, int(np.ceil(MARGIN_S * rate)))
    rng = np.random.default_rng(random_state)
    speed_change = central_difference(np.abs(F[:, 0]), bounds)
    pred = {k: np.full((N, 2), np.nan) for k in candidates}
    scored = np.zeros(N, bool)
    for j in range(N_FOLDS):
        held = np.flatnonzero(fold == j)
        if held.size == 0:
            continue
        near = np.zeros(N, bool)
        for m in range(-margin, margin + 1):
            near[np.clip(held + m, 0, N - 1)] = True
        train = np.flatnonzero(~near)
        if train.size <= candidates[0]:
            continue
        q = held if held.size <= _QUERIES_PER_FOLD else np.sort(rng.choice(held, _QUERIES_PER_FOLD, replace=False))
        kmax = min(candidates[-1], train.size)
        dist, idx = _query(cKDTree(Y[train]), Y[q], kmax)
        Zt, Ft = np.ascontiguousarray(Z[train], dtype=np.float32), F[train]
        for k in candidates:
            kk = min(k, kmax)
            for a in range(0, q.size, _BLOCK):
                sl = slice(a, a + _BLOCK)
                i = idx[sl, :kk]
                g = _solve(Zt[i], Ft[i], _weights(dist[sl, :kk]))
                pred[k][q[sl]] = (g @ Z[q[sl]].astype(np.float64)[:, :, None])[..., 0]
        scored[q] = True
    rows = []
    for k in candidates:
        p = pred[k][scored]
        accel = np.where(np.sign(p[:, 1]) == np.sign(p[:, 0]), 1.0, -1.0)
        rows.append((k, _agreement(p[:, 0], F[scored, 0]), _agreement(accel, speed_change[scored])))
    return rows

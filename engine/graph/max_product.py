"""Exact-length maximum-probability paths over a transition graph (the Viterbi core of paper 4.1).

A first-order Markov model of the states: :func:`log_transitions` and :func:`observed_transitions`
give its log-probabilities, :class:`MaxProductGraph` holds them as edges sorted by destination for
max-plus steps, and :func:`viterbi_path` finds the most probable path of exactly ``n`` frames
between two states. A path of ``n`` frames has ``n - 1`` transitions; self-transitions are allowed.
:mod:`engine.graph.bridges` runs the same steps only where such a path can pass.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["NoPathError", "MaxProductGraph", "log_transitions", "observed_transitions", "viterbi_path",
           "no_path_message"]


class NoPathError(ValueError):
    """No path of the requested length joins two states; the message names the gap."""


def log_transitions(P) -> sp.csr_matrix:
    """Log of a sparse transition matrix, keeping only its positive entries as edges.

    Parameters
    ----------
    P : sparse or dense (K, K)
        Transition probabilities ``P[j, k] = P(k | j)``.

    Returns
    -------
    csr_matrix (K, K)
        ``log P`` at every stored edge (0.0 entries are stored explicitly for P = 1).
    """
    P = sp.csr_matrix(P, dtype=np.float64)
    if P.shape[0] != P.shape[1]:
        raise ValueError(f"transition matrix must be square, got shape {P.shape}")
    coo = P.tocoo()
    keep = coo.data > 0
    if np.any(coo.data < 0):
        raise ValueError("transition probabilities must be >= 0")
    L = sp.coo_matrix((np.log(coo.data[keep]), (coo.row[keep], coo.col[keep])), shape=P.shape)
    return L.tocsr()


def observed_transitions(states) -> sp.csr_matrix:
    """P(k | j) over the transitions observed in the corpus (row-normalised ``counts_``).

    Unlike ``StateGraph.transition_`` this gives a state with no observed successor
    no edge at all (``transition_`` gives it a self-loop so that its rows sum to 1):
    a synthesised path only uses transitions the talker made.
    """
    C = getattr(states, "counts_", None)
    if C is None:
        return sp.csr_matrix(states.transition_)
    C = sp.csr_matrix(C, dtype=np.float64)
    out = np.asarray(C.sum(axis=1)).ravel()
    return sp.csr_matrix(sp.diags(1.0 / np.where(out > 0, out, 1.0)) @ C)


class MaxProductGraph:
    """Edges of a log-transition matrix sorted by destination, for max-plus steps.

    One step ``s'[k] = max_j s[j] + log P(k | j)`` costs O(E): gather the source
    scores on every edge, add the edge log-probabilities, and take a segment maximum
    over the edges of each destination (``np.maximum.reduceat``).

    Parameters
    ----------
    log_transition : sparse (K, K)
        Log-probabilities at the stored entries (every finite stored entry is an edge,
        explicit zeros included).
    """

    def __init__(self, log_transition):
        L = sp.coo_matrix(log_transition)
        if L.shape[0] != L.shape[1]:
            raise ValueError(f"log_transition must be square (K, K), got shape {L.shape}")
        if np.any(L.data > 1e-9) or np.any(np.isnan(L.data)):
            raise ValueError("log_transition must hold log-probabilities (<= 0, no NaN); "
                             "pass the log of P, e.g. log_transitions(P)")
        keep = np.isfinite(L.data)
        src, dst, w = L.row[keep], L.col[keep], L.data[keep].astype(np.float64)
        order = np.lexsort((src, dst))
        self.n_states = int(L.shape[0])
        self.src = src[order].astype(np.int64)
        self.dst = dst[order].astype(np.int64)
        self.logp = w[order]
        self.n_edges = int(self.src.size)
        if self.n_edges:
            change = np.flatnonzero(np.r_[True, self.dst[1:] != self.dst[:-1]])
        else:
            change = np.zeros(0, dtype=np.int64)
        self.starts = change
        self.targets = self.dst[change]  # destinations with at least one incoming edge
        self.seglen = np.diff(np.r_[change, self.n_edges])
        self._segment = np.full(self.n_states, -1, dtype=np.int64)  # state -> its segment of incoming edges
        self._segment[self.targets] = np.arange(self.targets.size)
        self.no_incoming = np.flatnonzero(self._segment < 0)

    def _run(self, scores, n_frames, keep_history=False):
        """``n_frames - 1`` max-plus steps from ``scores`` (M, K); optionally every step's scores."""
        cur = np.array(scores, dtype=np.float64)
        hist = [cur.copy()] if keep_history else None
        if int(n_frames) <= 1:
            return cur, hist
        nxt = np.full(cur.shape, -np.inf)
        buf = np.empty((cur.shape[0], self.n_edges))
        seg = np.empty((cur.shape[0], self.targets.size))
        for _ in range(int(n_frames) - 1):
            if self.n_edges:
                np.take(cur, self.src, axis=1, out=buf)
                buf += self.logp
                np.maximum.reduceat(buf, self.starts, axis=1, out=seg)
                nxt[:, self.targets] = seg
            nxt[:, self.no_incoming] = -np.inf  # never written: clear what the swap left there
            cur, nxt = nxt, cur
            if keep_history:
                hist.append(cur.copy())
        return cur, hist

    def forward(self, sources, n_frames) -> np.ndarray:
        """Best log-probability of an ``n_frames`` path from each source to every state.

        Parameters
        ----------
        sources : ndarray of shape (M,) int
        n_frames : int >= 1

        Returns
        -------
        ndarray of shape (M, K): ``-inf`` where no such path exists.
        """
        sources = np.asarray(sources, dtype=np.int64).reshape(-1)
        scores = np.full((sources.size, self.n_states), -np.inf)
        scores[np.arange(sources.size), sources] = 0.0
        return self._run(scores, n_frames)[0]

    def viterbi(self, a, n_frames):
        """Forward pass from one source keeping every step's scores for :meth:`backtrack`.

        Returns
        -------
        scores : ndarray (K,)
            Best log-probability of an ``n_frames`` path from ``a`` ending in each state.
        history : ndarray (n_frames, K)
            The scores after each step (row 0: the start).
        """
        scores = np.full((1, self.n_states), -np.inf)
        scores[0, int(a)] = 0.0
        last, hist = self._run(scores, n_frames, keep_history=True)
        return last[0], np.vstack(hist)

    def backtrack(self, history, b) -> np.ndarray:
        """The best path ending in state ``b`` after ``len(history)`` frames (ties: lowest predecessor)."""
        n = history.shape[0]
        path = np.empty(n, dtype=np.int64)
        path[-1] = int(b)
        for t in range(n - 1, 0, -1):
            k = self._segment[path[t]]
            lo = self.starts[k]
            hi = lo + self.seglen[k]
            path[t - 1] = self.src[lo + int(np.argmax(history[t - 1, self.src[lo:hi]] + self.logp[lo:hi]))]
        return path

    def hops(self, a) -> np.ndarray:
        """Fewest transitions from ``a`` to every state (inf if unreachable), for error messages."""
        from scipy.sparse.csgraph import shortest_path

        A = sp.csr_matrix((np.ones(self.n_edges), (self.src, self.dst)), shape=(self.n_states,) * 2)
        return shortest_path(A, unweighted=True, indices=int(a))


def viterbi_path(log_transition, a, b, n) -> np.ndarray:
    """Maximum-probability state path of exactly ``n`` frames from state ``a`` to state ``b``.

    Parameters
    ----------
    log_transition : sparse (K, K) or MaxProductGraph
        ``log P(k | j)`` at the observed transitions (see :func:`log_transitions`).
    a, b : int
        First and last state.
    n : int >= 1
        Frames in the path (``n - 1`` transitions; self-transitions allowed).

    Returns
    -------
    ndarray of shape (n,) int
        ``path[0] == a``, ``path[-1] == b``, each step an observed transition.

    Raises
    ------
    NoPathError
        When no path of exactly ``n`` frames joins ``a`` to ``b``.
    """
    g = log_transition if isinstance(log_transition, MaxProductGraph) else MaxProductGraph(log_transition)
    K = g.n_states
    for name, v in (("a", a), ("b", b)):
        if not 0 <= int(v) < K:
            raise ValueError(f"state {name}={v} out of range 0..{K - 1}")
    n = int(n)
    if n < 1:
        raise ValueError(f"a path needs at least 1 frame, got n={n}")
    scores, hist = g.viterbi(a, n)
    if not np.isfinite(scores[int(b)]):
        raise NoPathError(no_path_message(g, a, b, n))
    return g.backtrack(hist, b)


def no_path_message(g, a, b, n) -> str:
    """Why no path of exactly ``n`` frames joins states ``a`` and ``b`` of ``g`` (for :class:`NoPathError`)."""
    h = g.hops(a)[int(b)]
    if not np.isfinite(h):
        why = f"state {b} cannot be reached from state {a} at all"
    elif h + 1 > n:
        why = f"the shortest path from state {a} to {b} takes {int(h) + 1} frames"
    else:
        why = f"paths from state {a} to {b} exist but none of exactly {n} frames"
    return f"no path of exactly {n} frames from state {a} to state {b}: {why}"

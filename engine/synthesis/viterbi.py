"""Trajectory synthesis on the manifold: maximum-probability paths of a fixed length (paper 4.1).

Given timed key targets (states, F^y points or phones), every gap between two
consecutive targets is filled by the most probable state sequence of exactly the
gap's length under the first-order Markov model of the state graph, found with a
Viterbi (max-product) recursion over the sparse transition matrix. The trajectory
in Y is the sequence of state centroids; it is mapped back to X through the
Delaunay inverse map and to frames through the shape space.

Conventions
-----------
* A path of ``n`` frames has ``n - 1`` transitions; ``n = 1`` is the single state
  ``a`` (and needs ``a == b``). Self-transitions are allowed (the counts include
  them: a state held for several frames).
* Gaps share their end frames: a target at frame ``f_i`` closes gap ``i - 1`` and
  opens gap ``i``. Before the first target the first target is held, after the last
  the last (every method does the same, so they compare on equal terms).
* For targets given as phones (no state), each phone's candidate states are the
  ``n_candidates`` most frequent states of that phone's mid-point frames in the
  training corpus; a Viterbi over the lattice of candidates picks the sequence whose
  whole path is most probable, each gap scored by its best path's log-probability
  plus ``cluster_weight * log P(state | phone)``.

Baselines behind the same :class:`Synthesizer` interface: :class:`InterpolationSynthesizer`
("linear" and "cubic" interpolation of the targets in X) and
:class:`engine.synthesis.unitselection.UnitSelectionSynthesizer`.
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np
import scipy.sparse as sp
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from engine.constraints import Interval, StrOptions, validate_params
from engine.graph.bridges import bridge, forward_to
from engine.phonetics.targets import TargetSequence
from engine.phonetics.targets import resolve_phone as _resolve_phone
from engine.synthesis.trajectory import Synthesizer, Trajectory, interpolate_targets, smooth
from engine.synthesis.trajectory import check_fitted_manifold as _check_fitted_manifold
from engine.synthesis.trajectory import target_frames as _target_frames
from engine.threads import single_blas_thread

__all__ = [
    "NoPathError", "MaxProductGraph", "log_transitions", "observed_transitions", "viterbi_path", "Trajectory", "Synthesizer",
    "ManifoldSynthesizer", "InterpolationSynthesizer", "phone_lattice", "phone_state_table", "join_states",
]

#: log-probability cost of a gap no path of its length bridges (``strict=False`` lattices)
_UNBRIDGED_PENALTY = 1e6
#: inverse maps of :class:`ManifoldSynthesizer`
INVERSES = ("delaunay", "state-mean", "local-linear")


class NoPathError(ValueError):
    """No path of the requested length joins two states; the message names the gap."""


# ------------------------------------------------------------------ max-product core
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
        raise NoPathError(_no_path_message(g, a, b, n))
    return g.backtrack(hist, b)


def join_states(graph, frames, states, n_frames, centroids, *, on_miss=None):
    """The state path through ``states`` at ``frames``: each gap's maximum-probability path of exactly its length.

    Before the first target the path holds its state, after the last target the last
    state. A gap no path bridges in exactly its frames ends at the state, reachable in
    that many frames, whose centroid is nearest the target state's; when no path of
    that length leaves the gap's first state at all, the path holds it and jumps to
    the target state on the gap's last frame. Either way the next gap starts where
    this one ended.

    Parameters
    ----------
    graph : MaxProductGraph
        Log transition probabilities of the states.
    frames : ndarray of shape (T,) int
        Target frames, increasing.
    states : sequence of int, length T
        Target states.
    n_frames : int
        Frames of the path (> ``frames[-1]``).
    centroids : ndarray of shape (K, d)
        Where each state is, to find the reachable state nearest a missed target.
    on_miss : callable(gap, start, goal, end, n), optional
        Called for each missed gap with its index, first state, target state, the
        state it ends at (None when no path leaves ``start``) and its frames; it may
        raise to refuse the miss.

    Returns
    -------
    path : ndarray of shape (n_frames,) int64
    missed : int
        Gaps that could not reach their target state in exactly their length.
    """
    f = np.asarray(frames, dtype=np.int64)
    path = np.empty(int(n_frames), dtype=np.int64)
    path[: f[0] + 1] = states[0]
    cur, missed = int(states[0]), 0
    for g in range(len(f) - 1):
        n = int(f[g + 1] - f[g] + 1)
        goal = end = int(states[g + 1])
        seg = bridge(graph, cur, goal, n)  # the Viterbi path, scored only where it can pass
        if seg is None:
            missed += 1
            scores, back = graph.viterbi(cur, n)
            ok = np.flatnonzero(np.isfinite(scores))
            if ok.size:
                end = int(ok[np.argmin(np.linalg.norm(centroids[ok] - centroids[goal], axis=1))])
            if on_miss is not None:
                on_miss(g, cur, goal, end if ok.size else None, n)
            if ok.size:
                seg = graph.backtrack(back, end)
            else:
                seg = np.full(n, cur)
                seg[-1] = end
        path[f[g]: f[g + 1] + 1] = seg
        cur = int(seg[-1])
    path[f[-1]:] = path[f[-1]]
    return path, missed


def _no_path_message(g, a, b, n) -> str:
    h = g.hops(a)[int(b)]
    if not np.isfinite(h):
        why = f"state {b} cannot be reached from state {a} at all"
    elif h + 1 > n:
        why = f"the shortest path from state {a} to {b} takes {int(h) + 1} frames"
    else:
        why = f"paths from state {a} to {b} exist but none of exactly {n} frames"
    return f"no path of exactly {n} frames from state {a} to state {b}: {why}"


def _phone_state_table(manifold):
    """Per corpus phone label: (states, log P(state | phone)) sorted by frequency; labels most frequent first."""
    mids, labels, *_ = manifold.corpus_.phone_table()
    return phone_state_table(np.asarray(manifold.states_.labels_)[mids], labels)


def phone_state_table(states, labels) -> dict:
    """Per phone label: (states, log P(state | phone)) sorted by frequency, labels most frequent first.

    ``states`` (n,) int: the state of each phone instance's mid-point frame; ``labels`` (n,) str.
    """
    st, labels = np.asarray(states), np.asarray(labels)
    table = {}
    labs, counts = np.unique(labels, return_counts=True)
    for lab in labs[np.argsort(-counts, kind="stable")]:
        s, cnt = np.unique(st[labels == lab], return_counts=True)
        order = np.argsort(-cnt, kind="stable")
        table[str(lab)] = (s[order], np.log(cnt[order] / cnt.sum()))
    return table


class ManifoldSynthesizer(BaseEstimator):
    """The paper's synthesiser (method ``"viterbi"``): maximum-probability paths between timed targets on the state graph.

    Parameters
    ----------
    n_candidates : int, default=8
        M, candidate states per phone when targets are phones (the M most frequent
        states of the phone's mid-point frames in the training corpus).
    cluster_weight : float, default=1.0
        Weight of ``log P(state | phone)`` in the phone-target lattice (0: path
        probability only).
    strict : bool, default=True
        Raise :class:`NoPathError` when a gap cannot be bridged in exactly its number of
        frames. With ``strict=False`` the gap ends at the state reachable in exactly
        that many frames nearest (in Y) to the target (an undershoot, as when
        articulators cannot reach a target in time), the next gap starts there, and
        the trajectory's ``warnings`` say so; for phone targets, the lattice then
        prefers bridgeable candidate pairs and takes an unbridgeable one only when no
        other way exists.
    inverse_dims : int or None, default=None
        None: map the path back through the manifold's own inverse map (the paper's
        tetrahedralisation of the first 3 dims of F^y). An int d: tetrahedralise (in
        d dims) the first d dims of F^y, and place each state of the path at the mean
        F^y (first d dims) of its frames. More dims carry more of X (the paper notes
        the construction extends beyond 3), at the cost of a much larger triangulation
        (d = 5 on the paper-scale preset: 3.3 million simplices, ~30 s to build).
    inverse : {"delaunay", "state-mean", "local-linear"}, default="delaunay"
        How the state path becomes X. ``"delaunay"``: the tetrahedralisation above (the
        paper). ``"state-mean"``: each state's mean F^x over its training frames
        (:class:`engine.manifold.inverse_local.StateMeanInverse`; no triangulation, any number of
        state dims). ``"local-linear"``: the path's points (``points_``) through
        :class:`engine.manifold.inverse_local.LocalLinearInverse` on the first ``inverse_dims``
        (default: the state dims) of F^y, k = ``n_neighbors``.
    smoothing : float, default=0.0
        Gaussian smoothing of the path before the inverse map, in frames (X for
        ``"state-mean"``, the path's points in Y otherwise). ``engine.evaluation.protocols.select_settings``
        chooses it on training utterances.
    n_neighbors : int, default=40
        k of the ``"local-linear"`` inverse.

    Use ``fit(manifold)`` then ``synthesize(targets)``.

    Attributes
    ----------
    centroids_ : ndarray of shape (K, state_dims)
        State centroids (the path in Y).
    points_ : ndarray of shape (K, d)
        Where each state is mapped back from (``centroids_``, or the d-dim state means).
    n_states_ : int
    """

    method = "viterbi"
    _parameter_constraints = {
        "n_candidates": [Interval(Integral, 1, None, closed="left")],
        "cluster_weight": [Interval(Real, 0, None, closed="left")],
        "strict": ["boolean"],
        "inverse_dims": [Interval(Integral, 1, None, closed="left"), None],
        "inverse": [StrOptions(INVERSES)],
        "smoothing": [Interval(Real, 0, None, closed="left")],
        "n_neighbors": [Interval(Integral, 3, None, closed="left")],
    }

    def __init__(self, *, n_candidates=8, cluster_weight=1.0, strict=True, inverse_dims=None, inverse="delaunay",
                 smoothing=0.0, n_neighbors=40):
        self.n_candidates = n_candidates
        self.cluster_weight = cluster_weight
        self.strict = strict
        self.inverse_dims = inverse_dims
        self.inverse = inverse
        self.smoothing = smoothing
        self.n_neighbors = n_neighbors

    def fit(self, manifold):
        """Prepare the transition graph and phone candidate tables of a fitted manifold."""
        validate_params(self)
        _check_fitted_manifold(manifold)
        self._manifold = manifold
        self._graph = MaxProductGraph(log_transitions(observed_transitions(manifold.states_)))
        self._table = None
        self.centroids_ = np.asarray(manifold.states_.centroids_, dtype=np.float64)
        self.n_states_ = K = int(self.centroids_.shape[0])
        self._own_inverse = None
        if self.inverse_dims is None:
            self.points_ = self.centroids_
        else:
            d = int(self.inverse_dims)
            if not 1 <= d <= manifold.Fy_.shape[1]:
                raise ValueError(f"inverse_dims must be in 1..{manifold.Fy_.shape[1]} (the dims of F^y), got "
                                 f"{self.inverse_dims}; lower it or pass None for the manifold's own map")
            lab = np.asarray(manifold.states_.labels_)
            n = np.maximum(np.bincount(lab, minlength=K), 1)
            Fy = np.asarray(manifold.Fy_, dtype=np.float64)
            self.points_ = np.stack([np.bincount(lab, weights=Fy[:, j], minlength=K) for j in range(d)], 1) / n[:, None]
        return self

    # -- helpers ------------------------------------------------------------------
    def _path_x(self, path) -> np.ndarray:
        """X (n, m) of a state path through the chosen inverse map."""
        m = self._manifold
        if self.inverse == "state-mean":
            if self._own_inverse is None:
                from engine.manifold.inverse_local import StateMeanInverse

                self._own_inverse = StateMeanInverse().fit(m.states_.labels_, m.Fx_, n_states=self.n_states_)
            return smooth(self._own_inverse.transform(path), self.smoothing)
        P = smooth(self.points_[path], self.smoothing)
        if self.inverse == "local-linear":
            if self._own_inverse is None:
                from engine.manifold.inverse_local import LocalLinearInverse

                self._own_inverse = LocalLinearInverse(n_neighbors=int(self.n_neighbors),
                                                       n_dims=self.points_.shape[1]).fit(m.Fy_, m.Fx_)
            return self._own_inverse.transform(P)
        table = m.state_inverse() if hasattr(m, "state_inverse") else getattr(m, "state_x_", None)
        if (table is not None and self.inverse_dims is None and float(self.smoothing) == 0
                and table.shape[0] == self.n_states_):
            # the manifold file holds the Delaunay map of every state point: the same rows, no
            # tetrahedralisation in this process
            return np.asarray(table[path])
        return self._inverse().transform(P)

    def _inverse(self):
        m = self._manifold
        if self.inverse_dims is None and getattr(m, "inverse_map", None) is not None:
            return m.inverse_map
        if self._own_inverse is None:
            from engine.manifold.inverse import InverseMap

            d = int(self.inverse_dims) if self.inverse_dims is not None else min(3, m.Fy_.shape[1])
            self._own_inverse = InverseMap(n_dims=d).fit(m.Fy_, m.Fx_)
        return self._own_inverse

    def _candidates(self, label, warnings=None):
        if self._table is None:
            self._table = _phone_state_table(self._manifold)
        s, lp = self._table[_resolve_phone(label, list(self._table), warnings, "instances")]
        M = int(self.n_candidates)
        return s[:M], lp[:M]

    def _target_states(self, targets):
        """Oracle state per target, or None where the target has only a label."""
        out = []
        d = self.centroids_.shape[1]
        for t in targets.targets:
            if t.state is not None:
                if not 0 <= int(t.state) < self.n_states_:
                    raise ValueError(f"target state {t.state} out of range 0..{self.n_states_ - 1}")
                out.append(int(t.state))
            elif t.y is not None:
                y = np.asarray(t.y, dtype=np.float64).reshape(1, -1)[:, :d]
                out.append(int(self._manifold.states_.predict(y)[0]))
            else:
                out.append(None)
        return out

    # -- synthesis ----------------------------------------------------------------
    @single_blas_thread
    def synthesize(self, targets: TargetSequence) -> Trajectory:
        """Trajectory through ``targets`` (states / F^y points, or phone labels)."""
        check_is_fitted(self, "centroids_")
        f = _target_frames(targets)
        states = self._target_states(targets)
        warnings = []
        if any(s is None for s in states):
            states = self._choose_phone_states(targets, f, states, warnings)
        path = self._join(targets, f, states, warnings)
        Y = self.centroids_[path]
        Fx = np.asarray(self._path_x(path), dtype=np.float32)
        times = np.arange(targets.n_frames) / targets.rate
        return Trajectory(times=times, Fx=Fx, Fy=Y.astype(np.float32), method=self.method, states=path,
                          target_frames=f, target_labels=[t.label for t in targets.targets], warnings=warnings)

    def _gap_error(self, targets, f, g, exc):
        ta, tb = targets.targets[g], targets.targets[g + 1]
        return NoPathError(
            f"gap {g} between targets {ta.label or '?'!r} (frame {f[g]}) and {tb.label or '?'!r} "
            f"(frame {f[g + 1]}), {f[g + 1] - f[g] + 1} frames: {exc}; move the targets further apart, "
            "use fewer states (K), or synthesise with strict=False")

    def _join(self, targets, f, states, warnings):
        def missed(g, cur, goal, end, n):
            if self.strict:
                raise self._gap_error(targets, f, g, NoPathError(_no_path_message(self._graph, cur, goal, n)))
            if end is not None:
                warnings.append(f"gap {g} ({targets.targets[g].label!r} -> {targets.targets[g + 1].label!r}, "
                                f"{n} frames): target state {goal} unreachable in time; ended at state {end}")
            else:
                warnings.append(f"gap {g}: no path of {n} frames leaves state {cur}; held it and jumped "
                                f"to state {goal}")

        return join_states(self._graph, f, states, targets.n_frames, self.centroids_, on_miss=missed)[0]

    def _choose_phone_states(self, targets, f, fixed, warnings):
        """Viterbi over the lattice of candidate states per target (fixed targets: one candidate)."""
        cands, prior = [], []
        for t, s in zip(targets.targets, fixed):
            if s is not None:
                cands.append(np.array([s])), prior.append(np.zeros(1))
            else:
                c, lp = self._candidates(t.label, warnings)
                cands.append(c), prior.append(float(self.cluster_weight) * lp)
        return phone_lattice(self._graph, self.centroids_, cands, prior, f, strict=self.strict,
                             labels=[t.label for t in targets.targets], n_candidates=self.n_candidates)


def phone_lattice(graph, centroids, cands, prior, frames, *, strict=False, labels=None, n_candidates=None):
    """States of timed targets from candidate states each: a Viterbi over the lattice of candidates.

    Each gap between consecutive targets is scored by the log-probability of its best
    exact-length path (:func:`engine.graph.bridges.forward_to`), each candidate by its
    ``prior``; with ``strict=False`` an unbridgeable pair of candidates stays possible at
    a prohibitive cost (nearer pairs cheaper, by the distance of their ``centroids``).

    Parameters
    ----------
    graph : MaxProductGraph
    centroids : ndarray of shape (K, d)
    cands : list of ndarray (M_i,) int
        Candidate states per target.
    prior : list of ndarray (M_i,)
        Log-prior of each candidate.
    frames : ndarray of shape (T,) int
    strict : bool
        Raise :class:`NoPathError` when no candidate sequence can be bridged in time.
    labels : list of str, optional
        Target labels for messages.
    n_candidates : int, optional
        For the message.

    Returns
    -------
    list of int
        The chosen state per target.
    """
    f = np.asarray(frames, dtype=np.int64)
    delta = np.asarray(prior[0], dtype=np.float64).copy()
    backs = []
    for g in range(len(f) - 1):
        n = int(f[g + 1] - f[g] + 1)
        S = forward_to(graph, cands[g], n, cands[g + 1])  # (Mg, Mg+1), as forward(...)[:, cands[g + 1]]
        if not strict:
            # an unbridgeable pair stays possible at a prohibitive cost (nearer pairs cheaper);
            # the path then undershoots that gap
            d = np.linalg.norm(centroids[cands[g]][:, None] - centroids[cands[g + 1]][None], axis=2)
            S = np.where(np.isfinite(S), S, -_UNBRIDGED_PENALTY - d)
        tot = delta[:, None] + S
        bi = np.argmax(tot, axis=0)
        delta = tot[bi, np.arange(tot.shape[1])] + prior[g + 1]
        backs.append(bi)
        if not np.isfinite(delta).any():
            la = labels[g] if labels else "?"
            lb = labels[g + 1] if labels else "?"
            raise NoPathError(
                f"gap {g} between phones {la!r} (frame {f[g]}) and {lb!r} (frame {f[g + 1]}), "
                f"{n} frames: no path of exactly that length joins any of the candidate states of the phones "
                f"so far; lengthen the phones, raise n_candidates (now {n_candidates}), or use strict=False")
    j = int(np.argmax(delta))
    chosen = [0] * len(f)
    chosen[-1] = int(cands[-1][j])
    for g in range(len(f) - 2, -1, -1):
        j = int(backs[g][j])
        chosen[g] = int(cands[g][j])
    return chosen


# ------------------------------------------------------------------ direct interpolation
class InterpolationSynthesizer(BaseEstimator):
    """Direct interpolation of the phone targets in X ("linear" or "cubic" spline).

    A target's X is its oracle F^x when the target carries one, else the mean F^x of
    its phone's cluster (the mid-point frames of that phone in the training corpus).
    Outside the first and last target the value is held constant.

    Parameters
    ----------
    kind : {"linear", "cubic"}
        ``"cubic"`` uses :class:`scipy.interpolate.CubicSpline` (not-a-knot ends).
    """

    _parameter_constraints = {"kind": [StrOptions(("linear", "cubic"))]}

    def __init__(self, *, kind="linear"):
        self.kind = kind

    @property
    def method(self):
        return self.kind

    def fit(self, manifold):
        """Store the per-phone mean F^x of a fitted manifold's corpus."""
        validate_params(self)
        _check_fitted_manifold(manifold)
        mids, labels, *_ = manifold.corpus_.phone_table()
        labs, counts = np.unique(labels, return_counts=True)
        labs = labs[np.argsort(-counts, kind="stable")]  # most frequent first (stand-in phones)
        Fx = np.asarray(manifold.Fx_)
        self.phone_labels_ = [str(s) for s in labs]
        self.phone_means_ = (np.stack([Fx[mids[labels == lab]].mean(axis=0, dtype=np.float64) for lab in labs])
                             if labs.size else np.zeros((0, Fx.shape[1])))
        self.n_components_ = int(Fx.shape[1])
        return self

    def target_x(self, targets: TargetSequence, warnings=None) -> np.ndarray:
        """X of every target, ndarray of shape (T, m); phones the corpus lacks get a stand-in's mean."""
        check_is_fitted(self, "phone_means_")
        index = {lab: i for i, lab in enumerate(self.phone_labels_)}
        rows = []
        for t in targets.targets:
            if t.x is not None:
                x = np.asarray(t.x, dtype=np.float64).reshape(-1)
                if x.size != self.n_components_:
                    raise ValueError(f"target X has {x.size} components, the shape space {self.n_components_}")
                rows.append(x)
            else:
                rows.append(self.phone_means_[index[_resolve_phone(t.label, self.phone_labels_, warnings,
                                                                   "instances")]])
        return np.array(rows)

    @single_blas_thread
    def synthesize(self, targets: TargetSequence) -> Trajectory:
        check_is_fitted(self, "phone_means_")
        f = _target_frames(targets)
        warnings = []
        X = self.target_x(targets, warnings)
        t = np.arange(targets.n_frames, dtype=np.float64)
        out = interpolate_targets(self.kind, f, X, targets.n_frames)
        return Trajectory(times=t / targets.rate, Fx=out.astype(np.float32), Fy=None, method=self.kind,
                          target_frames=f, target_labels=[x.label for x in targets.targets], warnings=warnings)

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

The max-product core (:class:`MaxProductGraph`, :func:`viterbi_path`) is
:mod:`engine.graph.max_product`; the interpolation baselines behind the same
:class:`Synthesizer` interface are :mod:`engine.synthesis.interpolation` and
:mod:`engine.synthesis.unitselection`. Both are still importable from here, as scripts name them.
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np

from engine._deprecated import deprecated_names
from engine.constraints import Interval, StrOptions, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.graph.bridges import bridge, forward_to
from engine.graph.max_product import (
    MaxProductGraph,
    NoPathError,
    log_transitions,
    no_path_message,
    observed_transitions,
    viterbi_path,
)
from engine.phonetics.targets import TargetSequence
from engine.phonetics.targets import resolve_phone as _resolve_phone
from engine.synthesis.interpolation import InterpolationSynthesizer
from engine.synthesis.trajectory import Synthesizer, Trajectory, smooth
from engine.synthesis.trajectory import check_fitted_manifold as _check_fitted_manifold
from engine.synthesis.trajectory import target_frames as _target_frames
from engine.threads import single_blas_thread

__all__ = [
    "NoPathError", "MaxProductGraph", "log_transitions", "observed_transitions", "viterbi_path", "Trajectory",
    "Synthesizer",
    "ViterbiSynthesizer", "InterpolationSynthesizer", "phone_lattice", "phone_state_table", "join_states",
]

# the class's name before it said its method ("viterbi"); kept for scripts, with a warning
__getattr__ = deprecated_names(__name__, {"ManifoldSynthesizer": (__name__, "ViterbiSynthesizer")})

#: log-probability cost of a gap no path of its length bridges (``strict=False`` lattices)
_UNBRIDGED_PENALTY = 1e6
#: inverse maps of :class:`ViterbiSynthesizer`
INVERSES = ("delaunay", "state-mean", "local-linear")


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


class ViterbiSynthesizer(Estimator):
    """The paper's synthesiser (method ``"viterbi"``): maximum-probability paths between timed targets on the
    state graph.

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
        warnings: list[str] = []
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
                raise self._gap_error(targets, f, g, NoPathError(no_path_message(self._graph, cur, goal, n)))
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

"""State paths in a d-dimensional state space and every trajectory built from timed targets.

The synthesis of the paper (4.1) in any number of dimensions of Y, with its X taken
from the states, and the baselines that get the same information:

:class:`StateModel`
    K-means states of the first ``state_dims`` of F^y (an :class:`engine.graph.states.StateGraph`),
    the observed transitions between them, each state's mean F^x and mean velocity
    (:class:`engine.manifold.inverse_local.StateMeanInverse`) and a local-linear inverse
    (:class:`engine.manifold.inverse_local.LocalLinearInverse`) in the same dims.
:meth:`StateModel.path`
    The maximum-probability state path of exactly each gap's length between the
    target states (Viterbi, as :class:`engine.synthesis.viterbi.ViterbiSynthesizer`; a gap no
    path bridges in time ends at the reachable state nearest the target, as its
    ``strict=False``).
:meth:`StateModel.path_x`
    X of a path: ``"state-mean"`` (each state's mean F^x, then a Gaussian smoothing of
    ``sigma`` frames) or ``"local-linear"`` (the path of state centroids smoothed in Y,
    then mapped through the local-linear inverse).
:func:`anchor`
    A trajectory pulled onto given X at the target frames: the residuals at the targets
    are interpolated linearly over the frames between them and added.
:meth:`StateModel.hermite_x`
    The state-velocity Hermite spline: cubic Hermite through the target states' mean
    F^x (or given X at the targets) with the states' mean velocity F^x'.
:meth:`StateModel.learnt_x`
    The manifold synthesis: per shape component a validated base interpolation through
    the targets (the state-velocity Hermite spline, PCHIP, linear, or the spline with
    velocities calibrated on the targets, :mod:`engine.synthesis.calibration`) plus a
    validated share of the pooled training paths' deviation from it
    (:func:`engine.synthesis.learnt_paths.blend`).
:meth:`StateModel.phone_states`
    States of phone-only targets: a Viterbi over each phone's candidate states
    (:func:`engine.synthesis.viterbi.phone_lattice`).
:func:`engine.synthesis.trajectory.interpolate_targets`
    Direct interpolation of target X (the state-velocity Hermite spline's and the
    baselines' interpolation).

Every trajectory holds the first target before it and the last after it.
"""
from __future__ import annotations

import warnings as _warnings

import numpy as np

from engine.manifold.inverse_local import LocalLinearInverse, StateMeanInverse
from engine.synthesis.calibration import calibrated_spline
from engine.synthesis.learnt_paths import BASES, NEIGHBOR_STEPS, LearntPaths, blend
from engine.synthesis.trajectory import interpolate_targets, smooth

__all__ = ["StateModel", "anchor", "smooth", "PATH_INVERSES"]

PATH_INVERSES = ("state-mean", "local-linear")


def anchor(X, frames, X_targets) -> np.ndarray:
    """``X`` (n, m) plus the linearly interpolated residuals ``X_targets - X[frames]``.

    Equals ``X_targets`` at the target frames; outside the first and last target the
    nearest residual is held.
    """
    X = np.asarray(X, dtype=np.float64)
    f = np.asarray(frames, dtype=np.int64)
    R = np.asarray(X_targets, dtype=np.float64) - X[f]
    t = np.arange(X.shape[0], dtype=np.float64)
    return X + np.column_stack([np.interp(t, f, R[:, j]) for j in range(X.shape[1])])


class StateModel:
    """States of the first ``state_dims`` of F^y with their transitions and inverse maps.

    Parameters
    ----------
    state_dims : int
        Dimensions of F^y clustered (K-means).
    n_states : int or None
        K (None: :func:`engine.graph.states.default_n_states` of the frames).
    n_neighbors : int
        k of the local-linear inverse.
    random_state : int
    n_pool, duration_tolerance
        Of the learnt paths (:class:`engine.synthesis.learnt_paths.LearntPaths`).

    Use ``fit(Fy, Fx, Fxv, bounds, phones=None)``; the frames given are the only ones
    the model sees (a validation split passes its fitting part). ``phones`` =
    (mid-point frames (P,) into those rows, labels (P,)) enables :meth:`phone_states`.

    Attributes
    ----------
    graph_ : StateGraph
    inverse_ : StateMeanInverse
        Mean F^x and F^x' per state.
    local_ : LocalLinearInverse
    state_y_ : ndarray of shape (K, state_dims)
        Mean F^y (first ``state_dims``) per state.
    connectivity_warnings_ : list of str
        Warnings of the state graph (e.g. not strongly connected), kept, not raised.
    paths_ : LearntPaths
    phone_table_ : dict or None
        Phone label -> (candidate states, their log P(state | phone)), most frequent first.
    """

    def __init__(self, *, state_dims=5, n_states=None, n_neighbors=40, random_state=0, n_pool=128,
                 duration_tolerance=0.35):
        self.state_dims = state_dims
        self.n_states = n_states
        self.n_neighbors = n_neighbors
        self.random_state = random_state
        self.n_pool = n_pool
        self.duration_tolerance = duration_tolerance

    def fit(self, Fy, Fx, Fxv, bounds, phones=None, *, centroids=None):
        """Fit on the frames given; ``centroids`` (K, state_dims): state centres fitted before (a manifold
        file's :attr:`engine.manifold.model.Manifold.synthesis_states_`), so no K-means runs."""
        from engine.graph.max_product import MaxProductGraph, log_transitions, observed_transitions
        from engine.graph.states import StateGraph, default_n_states

        Fy = np.asarray(Fy)
        d = int(self.state_dims)
        if not 1 <= d <= Fy.shape[1]:
            raise ValueError(f"state_dims must be in 1..{Fy.shape[1]} (the dims of F^y), got {self.state_dims}")
        K = default_n_states(Fy.shape[0]) if self.n_states is None else int(self.n_states)
        with _warnings.catch_warnings(record=True) as caught:
            _warnings.simplefilter("always")
            self.graph_ = StateGraph(n_states=K, n_dims=d, random_state=self.random_state).fit(
                Fy, bounds, centroids=centroids)
        self.connectivity_warnings_ = [str(w.message) for w in caught]
        lab = self.graph_.labels_
        K = self.graph_.centroids_.shape[0]
        self.inverse_ = StateMeanInverse().fit(lab, Fx, Fxv, n_states=K)
        self.state_y_ = StateMeanInverse().fit(lab, np.asarray(Fy, np.float64)[:, :d], n_states=K).means_
        k = min(int(self.n_neighbors), Fy.shape[0])
        self.local_ = LocalLinearInverse(n_neighbors=max(k, d + 2), n_dims=d).fit(Fy, Fx)
        self._graph = MaxProductGraph(log_transitions(observed_transitions(self.graph_)))
        self.paths_ = LearntPaths(n_pool=self.n_pool, duration_tolerance=self.duration_tolerance).fit(
            Fy, Fx, bounds, lab, self.state_y_)
        self.phone_table_ = None
        if phones is not None:
            from engine.synthesis.viterbi import phone_state_table

            mids, labels = phones
            mids = np.asarray(mids, dtype=np.int64)
            if mids.size:
                self.phone_table_ = phone_state_table(lab[mids], np.asarray(labels))
        return self

    @property
    def n_states_(self) -> int:
        return int(self.graph_.centroids_.shape[0])

    def predict(self, Y) -> np.ndarray:
        """Nearest state of each point (n, >= state_dims) -> (n,) int."""
        return self.graph_.predict(Y).astype(np.int64)

    def path(self, frames, states, n_frames):
        """Viterbi state path through ``states`` at ``frames``, held outside them
        (:func:`engine.synthesis.viterbi.join_states`, a missed gap ending at the reachable
        state whose mean F^y is nearest the target's).

        Returns
        -------
        path : ndarray of shape (n_frames,) int
        missed : int
            Gaps that could not reach their target state in exactly their length.
        """
        from engine.synthesis.viterbi import join_states

        return join_states(self._graph, frames, [int(x) for x in states], n_frames, self.state_y_)

    def path_x(self, path, *, how="state-mean", sigma=0.0) -> np.ndarray:
        """X (n, m) of a state path by ``how`` in :data:`PATH_INVERSES`, smoothed by ``sigma`` frames."""
        if how == "state-mean":
            return smooth(self.inverse_.transform(path), sigma)
        if how == "local-linear":
            return self.local_.transform(smooth(self.state_y_[np.asarray(path)], sigma))
        raise ValueError(f"unknown path inverse {how!r}; choose from {', '.join(PATH_INVERSES)}")

    def hermite_x(self, frames, states, n_frames, x_targets=None) -> np.ndarray:
        """State-velocity Hermite (n_frames, m): through the states' mean F^x (or ``x_targets``)
        with their mean velocities."""
        st = np.asarray(states, dtype=np.int64)
        X = self.inverse_.means_[st] if x_targets is None else np.asarray(x_targets, dtype=np.float64)
        return interpolate_targets("hermite", frames, X, n_frames, self.inverse_.velocity_means_[st])

    def pooled_x(self, frames, states, n_frames, x_targets=None, neighbors=NEIGHBOR_STEPS) -> np.ndarray:
        """Pooled training paths between the target states (len(neighbors), n_frames, m)
        (:meth:`engine.synthesis.learnt_paths.LearntPaths.pooled`), pulled onto ``x_targets`` if given."""
        st = np.asarray(states, dtype=np.int64)
        return self.paths_.pooled(frames, self.state_y_[st], n_frames, neighbors, x_targets=x_targets,
                                  fallback=self.hermite_x(frames, st, n_frames, x_targets))

    def bases_x(self, frames, states, n_frames, x_targets=None, which=BASES) -> np.ndarray:
        """The base interpolations of :data:`engine.synthesis.learnt_paths.BASES` through the targets
        (len(BASES), n_frames, m); those not in ``which`` are zeros.

        ``"calibrated"`` is :func:`engine.synthesis.calibration.calibrated_spline` through
        ``x_targets``; without them (the targets are the states' own means) it is the
        state-velocity Hermite spline.
        """
        st = np.asarray(states, dtype=np.int64)
        X = self.inverse_.means_[st] if x_targets is None else np.asarray(x_targets, dtype=np.float64)
        V = self.inverse_.velocity_means_[st]
        out = np.zeros((len(BASES), int(n_frames), X.shape[1]))
        for i, kind in enumerate(BASES):
            if kind not in which:
                continue
            if kind == "calibrated" and x_targets is not None:
                out[i] = calibrated_spline(frames, X, V, n_frames)
            else:  # through the states' own means "calibrated" is the state-velocity spline
                out[i] = interpolate_targets("hermite" if kind == "calibrated" else kind, frames, X, n_frames, V)
        return out

    def learnt_x(self, frames, states, n_frames, weights, x_targets=None) -> np.ndarray:
        """The manifold synthesis (n_frames, m): per component a validated base interpolation plus the
        validated share of the pooled paths.

        ``weights``: ``base_index``, ``neighbor_index`` and ``beta`` per component, as
        :func:`engine.synthesis.learnt_paths.fit_blend` returns them.
        """
        idx = np.asarray(weights["neighbor_index"], dtype=np.int64)
        bidx = np.asarray(weights.get("base_index") or [0] * idx.size, dtype=np.int64)
        beta = np.asarray(weights["beta"], dtype=np.float64)
        used = sorted(set(idx[beta > 0].tolist())) or [0]
        P = self.pooled_x(frames, states, n_frames, x_targets, [NEIGHBOR_STEPS[i] for i in used]) \
            if np.any(beta > 0) else None
        full = np.zeros((len(NEIGHBOR_STEPS), int(n_frames), self.inverse_.means_.shape[1]))
        if P is not None:
            full[used] = P
        bases = self.bases_x(frames, states, n_frames, x_targets, {BASES[i] for i in set(bidx.tolist())})
        return blend(bases, full, bidx, idx, beta)

    def phone_states(self, frames, labels, *, n_candidates=8, cluster_weight=1.0, warnings=None,
                     fixed=None) -> np.ndarray:
        """States of phone-labelled targets by the phone lattice (strict=False: undershoot rather than fail).

        Phones the training frames lack take a stand-in phone's candidates (noted in
        ``warnings``). ``fixed`` (T,) holds a state for targets that have one (None for the
        others): the lattice keeps those and chooses the rest.
        """
        from engine.phonetics.targets import resolve_phone as _resolve_phone
        from engine.synthesis.viterbi import phone_lattice

        fixed = [None] * len(labels) if fixed is None else list(fixed)
        if not self.phone_table_ and any(s is None for s in fixed):
            raise ValueError("the state model was fitted without phones; phone targets need fit(..., phones=...)")
        known = list(self.phone_table_ or ())
        cands, prior = [], []
        for lab, st in zip(labels, fixed):
            if st is not None:
                cands.append(np.array([int(st)]))
                prior.append(np.zeros(1))
                continue
            s, lp = self.phone_table_[_resolve_phone(lab, known, warnings, "instances")]
            cands.append(s[: int(n_candidates)])
            prior.append(float(cluster_weight) * lp[: int(n_candidates)])
        return np.asarray(phone_lattice(self._graph, self.state_y_, cands, prior, frames, strict=False,
                                        labels=list(labels), n_candidates=n_candidates), dtype=np.int64)

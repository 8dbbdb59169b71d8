"""Every method of the three protocols: the trajectory each makes from what its protocol gives it.

``states``: the target states only (the state of each target frame's F^y)
    ==================  ==========================================================================
    ``manifold``        state-velocity Hermite plus the validated share of the training paths
                        between the states (:meth:`engine.synthesis.statepaths.StateModel.learnt_x`)
    ``viterbi``         the paper's path: the maximum-probability state path of exactly each
                        gap's length, X = each state's mean F^x, smoothed (sigma validated)
    ``sv-hermite``      state-velocity Hermite: cubic Hermite through the states' mean F^x with
                        the states' mean velocity F^x' (the manifold's dynamic features)
    ``pchip``           through the states' mean F^x (no dynamics)
    ``linear``          the same, straight lines
    ==================  ==========================================================================

``oracle``: the true X at the targets *and* the target states
    The same methods, every one through the true X (the two manifold paths pulled onto it,
    :func:`engine.synthesis.statepaths.anchor`).

``phones``: the phones and their times only (what ``lipspace synthesize --text`` has)
    ==================  ==========================================================================
    ``manifold``        as above, between the states the manifold's phone lattice chooses
                        (:meth:`engine.synthesis.statepaths.StateModel.phone_states`)
    ``viterbi``         the same
    ``unitselection``   concatenative unit selection (:mod:`engine.synthesis.unitselection`)
    ``dominance``       Cohen-Massaro coarticulation (:mod:`engine.synthesis.dominance`)
    ``sliding-window``  regression from windows of phone labels (:mod:`engine.synthesis.sliding_window`)
    ``linear``          through each phone's mean F^x at the phone mid-points
    ==================  ==========================================================================

Every protocol adds ``mean-frame``: the training mean frame, held.

:class:`PhoneModels` holds the phone-driven models fitted on one set of utterances;
:func:`trajectories` makes one held-out utterance's trajectory per protocol and method;
:func:`scores` measures one.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from engine.synthesis.statepaths import anchor
from engine.synthesis.trajectory import interpolate_targets

__all__ = ["PROTOCOLS", "PROTOCOL_METHODS", "METHOD_LABELS", "PhoneModels", "trajectories", "scores",
           "has_phone_labels", "SLIDING_WINDOW_CANDIDATES"]

PROTOCOLS = ("states", "oracle", "phones")
PROTOCOL_METHODS = {
    "states": ("manifold", "viterbi", "sv-hermite", "pchip", "linear", "mean-frame"),
    "oracle": ("manifold", "viterbi", "sv-hermite", "pchip", "linear", "mean-frame"),
    "phones": ("manifold", "viterbi", "unitselection", "dominance", "sliding-window", "linear", "mean-frame"),
}
METHOD_LABELS = {
    "manifold": "learnt paths between the states",
    "viterbi": "maximum-probability state path (the paper's)",
    "sv-hermite": "state-velocity Hermite",
    "pchip": "shape-preserving cubic (PCHIP)",
    "linear": "linear interpolation",
    "unitselection": "unit selection",
    "dominance": "Cohen-Massaro dominance",
    "sliding-window": "sliding-window regression",
    "mean-frame": "mean frame",
}
#: sliding-window settings tried on validation: (context frames, output window frames, ridge alpha)
SLIDING_WINDOW_CANDIDATES = ((12, 5, 3.0), (12, 9, 3.0), (24, 5, 3.0), (24, 9, 3.0), (24, 9, 30.0))


def has_phone_labels(corpus) -> bool:
    """True when the corpus has phone labels (not only kinematic landmarks standing in for them)."""
    from engine.recordings.kinematics import LANDMARK_LABELS

    labels = {p.label for u in corpus.utterances for p in u.phones}
    return bool(labels) and not labels <= set(LANDMARK_LABELS)


@dataclass
class PhoneModels:
    """The phone-driven models of the ``phones`` protocol, fitted on one set of utterances.

    Attributes
    ----------
    dominance : DominanceModel
    sliding : SlidingWindowRegressor
    units : UnitSelectionSynthesizer
    phone_means : dict of str to ndarray (m,)
        Mean F^x of each phone's mid-point frames.
    rate : float
    """

    dominance: object
    sliding: object
    units: object
    phone_means: dict
    rate: float

    @classmethod
    def fit(cls, manifold, utterances, *, sliding=(24, 9, 3.0), exclude=()):
        """Fit on ``utterances`` of ``manifold.corpus_`` (unit selection: every utterance not in ``exclude``)."""
        from engine.synthesis.dominance import DominanceModel
        from engine.synthesis.sliding_window import SlidingWindowRegressor
        from engine.synthesis.trajectory import phone_sequences
        from engine.synthesis.unitselection import UnitSelectionSynthesizer

        c = manifold.corpus_
        seqs = phone_sequences(utterances, manifold.Fx_)
        ctx, ow, alpha = sliding
        return cls(dominance=DominanceModel().fit(seqs, c.rate),
                   sliding=SlidingWindowRegressor(context=int(ctx), output_window=int(ow), alpha=float(alpha)).fit(
                       seqs, c.rate),
                   units=UnitSelectionSynthesizer(exclude_utterances=tuple(exclude)).fit(manifold),
                   phone_means=phone_means(seqs, c.rate), rate=float(c.rate))


def phone_means(sequences, rate) -> dict:
    """Mean X of each phone's mid-point frames over (X, phones) sequences, most frequent phone first."""
    acc: dict[str, Any] = {}
    for X, phones in sequences:
        for p in phones:
            f = int(np.clip(round(p.mid * rate), 0, X.shape[0] - 1))
            acc.setdefault(p.label, []).append(X[f])
    order = sorted(acc, key=lambda k: -len(acc[k]))
    return {k: np.mean(acc[k], axis=0) for k in order}


def _phone_linear(models, tg, warnings=None):
    from engine.phonetics.targets import resolve_phone as _resolve_phone

    known = list(models.phone_means)
    X = np.array([models.phone_means[_resolve_phone(t.label, known, warnings, "instances")] for t in tg.targets])
    return interpolate_targets("linear", tg.frames, X, tg.n_frames)


def trajectories(sm, settings, tg, states, mean_x, *, phone_models=None, protocols=PROTOCOLS,
                 lattice_states=None):
    """Every method's X (n, m) per protocol for one utterance's targets.

    Parameters
    ----------
    sm : StateModel
        Fitted on the training frames.
    settings : dict
        ``sigma`` ("protocol/viterbi" -> frames) and ``blend`` (protocol -> the weights of
        :func:`engine.synthesis.learnt_paths.fit_blend`), as :func:`engine.evaluation.protocols.select_settings` gives.
    tg : TargetSequence
        The utterance's targets (frames, labels, oracle X) and phones.
    states : ndarray of shape (T,) int
        The target states.
    mean_x : ndarray of shape (m,)
    phone_models : PhoneModels, optional
        Needed by the ``phones`` protocol.
    lattice_states : ndarray of shape (T,) int, optional
        The phone lattice's states (computed when None).

    Returns
    -------
    out : dict of protocol -> dict of method -> ndarray (n, m)
    missed : int
        Gaps of the Viterbi paths that could not reach their target in time.
    """
    f, n = tg.frames, tg.n_frames
    st = np.asarray(states, dtype=np.int64)
    Xo = np.array([t.x for t in tg.targets], dtype=np.float64) if "oracle" in protocols else None
    sig, bl = settings["sigma"], settings["blend"]
    out, missed = {}, 0
    if "states" in protocols or "oracle" in protocols:
        path, missed = sm.path(f, st, n)
        Xs = sm.inverse_.means_[st]
        Vs = sm.inverse_.velocity_means_[st]
    if "states" in protocols:
        out["states"] = {"manifold": sm.learnt_x(f, st, n, bl["states"]),
                         "viterbi": sm.path_x(path, how="state-mean", sigma=sig["states/viterbi"]),
                         "sv-hermite": sm.hermite_x(f, st, n),
                         "pchip": interpolate_targets("pchip", f, Xs, n),
                         "linear": interpolate_targets("linear", f, Xs, n)}
    if "oracle" in protocols:
        out["oracle"] = {"manifold": sm.learnt_x(f, st, n, bl["oracle"], x_targets=Xo),
                         "viterbi": anchor(sm.path_x(path, how="state-mean", sigma=sig["oracle/viterbi"]), f, Xo),
                         "sv-hermite": interpolate_targets("hermite", f, Xo, n, Vs),
                         "pchip": interpolate_targets("pchip", f, Xo, n),
                         "linear": interpolate_targets("linear", f, Xo, n)}
    if "phones" in protocols:
        if phone_models is None:
            raise ValueError("the phones protocol needs the phone models (PhoneModels.fit)")
        ls = sm.phone_states(f, tg.labels) if lattice_states is None else np.asarray(lattice_states, np.int64)
        lpath, _ = sm.path(f, ls, n)
        out["phones"] = {"manifold": sm.learnt_x(f, ls, n, bl["phones"]),
                         "viterbi": sm.path_x(lpath, how="state-mean", sigma=sig["phones/viterbi"]),
                         "unitselection": np.asarray(phone_models.units.synthesize(tg.phones_only()).Fx, np.float64),
                         "dominance": phone_models.dominance.predict(tg.phones, n, tg.rate),
                         "sliding-window": phone_models.sliding.predict(tg.phones, n, tg.rate),
                         "linear": _phone_linear(phone_models, tg)}
    for p in out:
        out[p]["mean-frame"] = np.repeat(np.asarray(mean_x, np.float64)[None], n, axis=0)
    return out, missed


def scores(manifold, X, F, lo, hi, *, Y_true=None, y_dims=3, gaps=None) -> dict:
    """Sums over frames [lo, hi) of one trajectory's errors against the real frames ``F`` (n, C).

    Returns ``frames``, ``sq_x`` (squared Euclidean error in X), ``lve_sum`` (per frame the
    largest per-point error), ``sq_v`` over ``frames_v`` (velocity error: the first
    difference of X against the real one), ``acc`` and ``acc_true`` (squared second
    differences of the trajectory and of the real one), with ``Y_true`` ``sq_y`` (the
    first ``y_dims`` of Y, the trajectory projected out-of-sample), and with ``gaps`` (the
    target frames, increasing, from ``lo`` to ``hi - 1``) the sums per gap between them:
    ``gap_frames``, ``gap_sq_x`` and ``gap_lve`` (lists; the last gap holds its end frame).
    """
    X = np.asarray(X, dtype=np.float64)
    Xt = manifold.shape_.transform(F[lo:hi]).astype(np.float64)
    Xh = X[lo:hi]
    n = hi - lo
    dims = manifold.corpus_.dims
    Fh = manifold.shape_.inverse_transform(Xh.astype(np.float32)).astype(np.float64).reshape(n, -1, dims)
    lve = np.linalg.norm(Fh - np.asarray(F[lo:hi], np.float64).reshape(n, -1, dims), axis=2).max(axis=1)
    out = {"frames": n, "sq_x": float(((Xh - Xt) ** 2).sum()), "lve_sum": float(lve.sum()),
           "sq_v": float(((np.diff(Xh, axis=0) - np.diff(Xt, axis=0)) ** 2).sum()), "frames_v": n - 1,
           "acc": float((np.diff(Xh, 2, axis=0) ** 2).sum()), "acc_true": float((np.diff(Xt, 2, axis=0) ** 2).sum())}
    if gaps is not None and len(gaps) >= 2:
        cuts = np.append(np.asarray(gaps, dtype=np.int64)[:-1], hi) - lo
        sq = ((Xh - Xt) ** 2).sum(axis=1)
        out["gap_frames"] = np.diff(cuts).tolist()
        out["gap_sq_x"] = np.add.reduceat(sq, cuts[:-1]).tolist()
        out["gap_lve"] = np.add.reduceat(lve, cuts[:-1]).tolist()
    if Y_true is not None:
        from engine.manifold.model import project_x

        Yh = project_x(manifold, X)[lo:hi, :y_dims].astype(np.float64)
        out["sq_y"] = float(((Yh - np.asarray(Y_true, np.float64)[lo:hi, :y_dims]) ** 2).sum())
    return out

"""Held-out synthesis under three protocols in which every method gets the same information.

Whole utterances are held out; everything is fitted on the rest. The targets of a
held-out utterance are its phone mid-point frames (collisions merged; kinematic
landmarks for a corpus without phones). The protocols and their methods are those of
:mod:`engine.synthesis.protocol_methods`: ``states`` (the target states only), ``oracle`` (the
true X at the targets and the target states) and ``phones`` (the phones and their times
only; run when the corpus has phone labels).

Scores over the frames from the first to the last target, every method alike:
``rmse_x`` (Euclidean error in X, RMS over frames), ``rmse_y`` (the first :data:`Y_DIMS`
dims of Y; *every* trajectory projected out-of-sample through the same fitted pipeline,
:func:`engine.manifold.model.project_x`, against the held-out utterance's own projection),
``lve`` (lip-vertex error: per frame the largest Euclidean error over the points, in the
corpus's units, averaged over frames), ``vel`` (RMSE of the velocity F^x', the first
difference, against the real one) and ``smooth`` (RMS second difference of the
trajectory over that of the real lips: 1 is as rough as the capture, below 1 smoother).
Per-utterance differences to ``manifold`` are summarised with a bootstrap CI, a sign test
and a signed-rank test (:mod:`engine.evaluation.paired`).

Settings are chosen on a validation split of the *training* utterances
(:func:`select_settings`), never on held-out results: ``state_dims``, the number of states
K, per protocol the manifold method's share of the learnt paths per shape component,
the Viterbi path's smoothing, k of the local-linear inverse (for the inverse-map table)
and the sliding-window regression's window and penalty. The same split measures every
method, and the method with the smallest validation RMSE X per protocol is the one the
explorer and ``lipspace synthesize`` use by default (:mod:`engine.synthesis.method_choice`).
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from engine.progress import ProgressFn, report
from engine.synthesis.protocol_methods import (
    PROTOCOL_METHODS,
    PROTOCOLS,
    PhoneModels,
    has_phone_labels,
    scores,
    trajectories,
)
from engine.synthesis.statepaths import StateModel
from engine.synthesis.trajectory import phone_mids
from engine.synthesis.validation import (
    FRAMES_PER_STATE_CANDIDATES,
    MIN_VALIDATION_UTTERANCES,
    SMOOTHING_CANDIDATES,
    STATE_DIM_CANDIDATES,
    Y_DIMS,
    mid_frames,
    select_settings,
)

if TYPE_CHECKING:
    from engine.evaluation.protocol_report import ProtocolResult
    from engine.manifold.model import Manifold
    from engine.recordings.corpus import Corpus

__all__ = ["PROTOCOLS", "PROTOCOL_METHODS", "STATE_DIM_CANDIDATES", "FRAMES_PER_STATE_CANDIDATES",
           "SMOOTHING_CANDIDATES", "Y_DIMS", "MIN_VALIDATION_UTTERANCES",
           "select_settings", "evaluate_protocols", "split_utterances", "fit_on_training_split"]


def split_utterances(corpus: Corpus, *, test_fraction: float = 0.1, test_ids: Sequence[str] | None = None,
                     random_state: int | None = 0) -> tuple[list[str], list[str]]:
    """Split a corpus's utterances into training and held-out ones.

    Parameters
    ----------
    corpus : Corpus
        At least two utterances.
    test_fraction : float, default=0.1
        In (0, 1): the share held out, at least one utterance and at most all but one;
        ignored with ``test_ids``.
    test_ids : sequence of str, optional
        Hold out exactly these utterances.
    random_state : int, default=0
        Seeds the random choice of the held-out utterances.

    Returns
    -------
    train_ids, test_ids : list of str
        Training ids in corpus order; held-out ids as given, else in corpus order.
    """
    ids = [u.id for u in corpus.utterances]
    if len(ids) < 2:
        raise ValueError(f"{corpus.name} has {len(ids)} utterance(s); holding out whole utterances needs at least 2")
    if test_ids is not None:
        test = [str(t) for t in test_ids]
        unknown = [t for t in test if t not in ids]
        if unknown:
            raise ValueError(f"test utterance(s) {unknown[:5]} not in {corpus.name}; it has {ids[:8]}...")
        if len(set(test)) >= len(ids):
            raise ValueError("every utterance is a test utterance; leave at least one for training")
    else:
        if not 0 < float(test_fraction) < 1:
            raise ValueError(f"test_fraction must be in (0, 1), got {test_fraction}")
        k = min(len(ids) - 1, max(1, int(round(float(test_fraction) * len(ids)))))
        rng = np.random.default_rng(random_state)
        picked = sorted(rng.choice(len(ids), size=k, replace=False).tolist())
        test = [ids[i] for i in picked]
    ts = set(test)
    return [i for i in ids if i not in ts], test


def fit_on_training_split(corpus: Corpus, *, test_fraction: float = 0.1, test_ids: Sequence[str] | None = None,
                          random_state: int | None = 0,
                          manifold_factory: Callable[[Corpus], Manifold] | None = None,
                          progress: ProgressFn = None) -> tuple[list[str], list[str], Corpus, Manifold]:
    """Split ``corpus`` by whole utterances (:func:`split_utterances`) and fit a manifold on the training part only.

    Returns
    -------
    train_ids, test_ids : list of str
    train : Corpus
        The training utterances.
    manifold : Manifold
        ``manifold_factory(train)``, or ``Manifold(random_state=random_state)`` fitted on ``train``.
    """
    train_ids, test = split_utterances(corpus, test_fraction=test_fraction, test_ids=test_ids,
                                       random_state=random_state)
    train = corpus.subset(train_ids)
    if manifold_factory is None:
        from engine.manifold.model import Manifold

        manifold = Manifold(random_state=random_state).fit(train, progress=progress)
    else:
        manifold = manifold_factory(train)
    return train_ids, test, train, manifold


def evaluate_protocols(corpus: Corpus, *, test_fraction: float = 0.1, test_ids: Sequence[str] | None = None,
                       random_state: int | None = 0, manifold_factory: Callable[[Corpus], Manifold] | None = None,
                       settings: dict[str, Any] | None = None,
                       settings_factory: Callable[[Manifold], dict[str, Any]] | None = None, n_boot: int = 2000,
                       inverse_table: bool = True, phones: bool | None = None,
                       progress: ProgressFn = None) -> ProtocolResult:
    """Hold out utterances, fit on the rest, run every protocol; see the module docstring.

    Parameters
    ----------
    corpus : Corpus
    test_fraction, test_ids, random_state
        As :func:`split_utterances`.
    manifold_factory : callable(train corpus) -> fitted Manifold, optional
    settings : dict, optional
        As returned by :func:`select_settings` (default: chosen by it on the training utterances).
    settings_factory : callable(fitted Manifold) -> dict, optional
        Makes the settings from the training manifold when ``settings`` is None.
    n_boot : int
        Bootstrap resamples of the paired comparisons.
    inverse_table : bool
        Also reconstruct the held-out frames' X from their own F^y with each inverse map
        (the paper's 3-D Delaunay, local-linear in 3 and ``state_dims`` dims, state means).
    phones : bool or None
        Run the phones protocol (None: when the corpus has phone labels).

    Returns
    -------
    ProtocolResult
    """
    from engine.evaluation.protocol_report import ProtocolResult

    train_ids, test, train, manifold = fit_on_training_split(
        corpus, test_fraction=test_fraction, test_ids=test_ids, random_state=random_state,
        manifold_factory=manifold_factory, progress=progress)
    phones = has_phone_labels(train) if phones is None else bool(phones)
    if settings is None:
        settings = (settings_factory(manifold) if settings_factory is not None
                    else select_settings(manifold, random_state=random_state, phones=phones, progress=progress))
    protos = tuple(p for p in settings.get("protocols", PROTOCOLS) if p != "phones" or phones)
    d = int(settings["state_dims"])
    c = manifold.corpus_
    sm = StateModel(state_dims=d, n_states=settings.get("n_states"), n_neighbors=int(settings["n_neighbors"]),
                    random_state=random_state).fit(manifold.Fy_, manifold.Fx_, manifold.Fxv_, c.bounds,
                                                   phones=phone_mids(c, c.utterances) if phones else None)
    models = None
    if "phones" in protos:
        models = PhoneModels.fit(manifold, c.utterances, sliding=tuple(settings["sliding_window"]))
    mean_x = np.asarray(manifold.Fx_, dtype=np.float64).mean(axis=0)
    inv: dict[str, Any]
    per, failures, missed, inv = [], [], 0, {}
    for j, uid in enumerate(test):
        report(progress, "protocols", j, len(test))
        u = corpus.utterance(uid)
        F = corpus.frames[u.start:u.stop]
        try:
            tg = mid_frames(manifold, uid, corpus)
            Y = manifold.project(F).astype(np.float64)
            st = sm.predict(Y[tg.frames, :d])
            trajs, miss = trajectories(sm, settings, tg, st, mean_x, phone_models=models, protocols=protos)
        except ValueError as exc:
            failures.append(f"{uid}: {exc}")
            continue
        missed += miss
        lo, hi = int(tg.frames[0]), int(tg.frames[-1]) + 1
        for p, methods in trajs.items():
            for m, X in methods.items():
                per.append({"protocol": p, "method": m, "utterance": uid,
                            **scores(manifold, X, F, lo, hi, Y_true=Y, y_dims=Y_DIMS, gaps=tg.frames)})
        if inverse_table:
            _inverse_errors(inv, manifold, sm, F, Y)
    report(progress, "protocols", len(test), len(test))
    return ProtocolResult.build(per, corpus=corpus.name, test_ids=test, train_ids=train_ids,
                                n_train_frames=train.n_frames, settings=settings, failures=failures,
                                missed_gaps=missed, inverse=inv, n_states=sm.n_states_,
                                state_warnings=sm.connectivity_warnings_, n_boot=n_boot, random_state=random_state,
                                manifold=manifold)


def _inverse_errors(acc: dict[str, Any], manifold: Manifold, sm: StateModel, F: np.ndarray, Y: np.ndarray) -> None:
    """Accumulate squared X error and LVE of each inverse map on one held-out utterance's own F^y."""
    from engine.manifold.inverse_local import LocalLinearInverse

    d = int(sm.graph_.n_dims)
    n = F.shape[0]
    dims = manifold.corpus_.dims
    Xt = manifold.shape_.transform(F).astype(np.float64)
    if "_ll3" not in acc:
        acc["_ll3"] = LocalLinearInverse(n_neighbors=sm.local_.n_neighbors, n_dims=3).fit(manifold.Fy_, manifold.Fx_)
    maps = {"delaunay-3d (paper)": lambda: manifold.inverse_map.transform(Y[:, :3]),
            "local-linear-3d": lambda: acc["_ll3"].transform(Y),
            f"local-linear-{d}d": lambda: sm.local_.transform(Y),
            f"state-mean-{d}d": lambda: sm.inverse_.transform(sm.predict(Y))}
    for name, fn in maps.items():
        X = np.asarray(fn(), dtype=np.float64)
        Fh = manifold.shape_.inverse_transform(X.astype(np.float32)).astype(np.float64).reshape(n, -1, dims)
        lv = np.linalg.norm(Fh - F.astype(np.float64).reshape(n, -1, dims), axis=2).max(axis=1)
        a = acc.setdefault(name, {"sq_x": 0.0, "lve_sum": 0.0, "frames": 0, "sq_comp": 0.0, "var_comp": 0.0})
        a["sq_x"] += float(((X - Xt) ** 2).sum())
        a["sq_comp"] = a["sq_comp"] + ((X - Xt) ** 2).sum(axis=0)  # per component, for R^2
        a["var_comp"] = a["var_comp"] + ((Xt - np.asarray(manifold.Fx_, np.float64).mean(axis=0)) ** 2).sum(axis=0)
        a["lve_sum"] += float(lv.sum())
        a["frames"] += n

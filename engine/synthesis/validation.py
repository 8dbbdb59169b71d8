"""Settings of the synthesis methods, chosen on a validation split of the training utterances.

:func:`select_settings` splits off a fifth of the training utterances (whole utterances),
or, for a corpus too small to give that split :data:`MIN_SPLIT_UTTERANCES` of them, holds
each training utterance out in turn (leave one out, pooled over the folds),
fits the state model on the rest and measures, per protocol of
:mod:`engine.synthesis.protocol_methods`, every candidate setting and every method:
``state_dims``, the number of states K, the manifold method's share of the learnt paths
per shape component, the Viterbi path's smoothing, k of the local-linear inverse and the
sliding-window regression's window and penalty. The method with the smallest validation
RMSE X per protocol is the one :mod:`engine.synthesis.method_choice` makes the default.
Held-out evaluation (:mod:`engine.evaluation.protocols`) calls the same functions on its
training utterances and never looks at held-out results here.

The validation's cost is bounded at any corpus size (:func:`default_fit_frames`): a fit
split larger than the budget -- the frames at which the smallest frames-per-state
candidate reaches the state graph's cap on K -- is replaced by a random subset of its
whole utterances within the budget, the validation utterances by a subset in the same
proportion, and K (the candidates and the chosen ``n_states``) is capped as the state
graph caps its default. A fit split within the budget is validated exactly as before.
"""
from __future__ import annotations

import numpy as np

from engine.graph.states import MAX_DEFAULT_STATES
from engine.manifold.inverse_local import NEIGHBOR_CANDIDATES, select_neighbors
from engine.progress import ProgressFn, report
from engine.synthesis.learnt_paths import BASES, NEIGHBOR_STEPS, BlendAccumulator, fit_blend, prior_blend
from engine.synthesis.protocol_methods import (
    PROTOCOLS,
    SLIDING_WINDOW_CANDIDATES,
    PhoneModels,
    has_phone_labels,
    scores,
    trajectories,
)
from engine.synthesis.statepaths import StateModel, anchor
from engine.synthesis.trajectory import phone_mids

__all__ = ["STATE_DIM_CANDIDATES", "FRAMES_PER_STATE_CANDIDATES", "SMOOTHING_CANDIDATES", "Y_DIMS",
           "MIN_VALIDATION_UTTERANCES", "MIN_SPLIT_UTTERANCES", "select_settings", "default_fit_frames", "manifold_y",
           "mid_frames"]

STATE_DIM_CANDIDATES = (3, 5, 8)
#: K candidates: one state per this many training frames (30: the state graph's default)
FRAMES_PER_STATE_CANDIDATES = (30, 15, 8)
SMOOTHING_CANDIDATES = (0.0, 1.0, 2.0, 3.0, 4.0, 6.0)
Y_DIMS = 3
#: training utterances below which there is no validation split (fixed defaults instead)
MIN_VALIDATION_UTTERANCES = 3
#: validation utterances a single split must hold: fewer cannot show a two-sided sign test at p < 0.05 between two
#: methods, so a smaller corpus is validated by leave one out (where its frames allow: :func:`_splits`)
MIN_SPLIT_UTTERANCES = 6


def _slice_rows(A, utts):
    return np.concatenate([A[u.start:u.stop] for u in utts])


def default_fit_frames(frames_per_state=FRAMES_PER_STATE_CANDIDATES) -> int:
    """The fit split's frame budget: ``MAX_DEFAULT_STATES * min(frames_per_state)`` (3000 * 8 = 24,000).

    The most frames on which every K candidate (one state per ``frames_per_state``
    frames) stays within the state graph's cap on its default K
    (:data:`engine.graph.states.MAX_DEFAULT_STATES`), so a fit split within it is
    validated as it always was, and a larger one costs what this many frames cost.
    """
    fps = [float(f) for f in frames_per_state]
    if not fps or min(fps) <= 0:
        raise ValueError(f"frames_per_state must be positive numbers of frames, got {list(frames_per_state)}")
    return int(MAX_DEFAULT_STATES * min(fps))


def _check_fit_frames(max_fit_frames, frames_per_state):
    if max_fit_frames is None:
        return default_fit_frames(frames_per_state)
    try:
        v = float(max_fit_frames)
    except (TypeError, ValueError):
        v = float("nan")
    if isinstance(max_fit_frames, bool) or not v >= 2:
        raise ValueError(f"max_fit_frames must be a number of frames >= 2 (math.inf: no bound), got "
                         f"{max_fit_frames!r}; pass None for the default budget of "
                         f"{default_fit_frames(frames_per_state)} "
                         f"frames (MAX_DEFAULT_STATES {MAX_DEFAULT_STATES} x the smallest frames per state)")
    return v


def _within(utts, budget, rng, keep):
    """A random subset of whole ``utts`` (in corpus order) whose frames stay within ``budget``; at least ``keep``."""
    chosen, total = [], 0
    for i in rng.permutation(len(utts)).tolist():
        n = utts[i].n_frames
        if total + n <= budget or len(chosen) < keep:
            chosen.append(i)
            total += n
    return [utts[i] for i in sorted(chosen)]


def _bounds(utts):
    n = np.cumsum([0] + [u.n_frames for u in utts])
    return np.column_stack([n[:-1], n[1:]])


def mid_frames(manifold, uid, corpus=None):
    from engine.phonetics.targets import targets_from_utterance

    return targets_from_utterance(manifold, uid, corpus=corpus, on_collision="merge")


def _defaults(manifold, cand, n_states, ids, phones):
    d = min(cand, key=lambda x: abs(x - 5))
    m = int(manifold.Fx_.shape[1])
    protos = PROTOCOLS if phones else PROTOCOLS[:2]
    return {"state_dims": d, "n_neighbors": 40, "n_states": n_states, "frames_per_state": None,
            "sigma": {f"{p}/viterbi": 2.0 for p in protos}, "blend": {p: prior_blend(m) for p in protos},
            "sliding_window": SLIDING_WINDOW_CANDIDATES[-2], "protocols": list(protos), "validation": {},
            "method_validation": {}, "best": {}, "val_ids": [],
            "note": f"only {len(ids)} training utterance(s): no validation split; fixed defaults (state_dims {d}, "
                    f"default K, k 40, Viterbi smoothing 2 frames; the manifold method without validated learnt "
                    f"share is the Hermite spline with calibrated state velocities)"}


class _Val:
    """The validation utterances with what every candidate setting needs of them."""

    def __init__(self, manifold, val):
        self.m, self.utts = manifold, val
        self.targets = [mid_frames(manifold, u.id) for u in val]
        self.X = [np.asarray(manifold.Fx_[u.start:u.stop], dtype=np.float64) for u in val]
        self.F = [manifold.corpus_.frames[u.start:u.stop] for u in val]

    def span(self, i):
        f = self.targets[i].frames
        return int(f[0]), int(f[-1]) + 1


class _Fold:
    """One split of the training utterances: the fitting part's rows and the validation utterances."""

    def __init__(self, manifold, fit, val, phones):
        self.fit = fit
        self.Fy, self.Fx, self.Fxv = (_slice_rows(A, fit) for A in (manifold.Fy_, manifold.Fx_, manifold.Fxv_))
        self.bounds = _bounds(fit)
        self.mids = phone_mids(manifold.corpus_, fit) if phones else None
        self.Fy_val = _slice_rows(manifold.Fy_, val)
        self.Fx_val = _slice_rows(manifold.Fx_, val).astype(np.float64)
        self.V = _Val(manifold, val)


def _splits(corpus, val_fraction, rng, budget):
    """The validation's folds, [(fit utterances, validation utterances), ...], and what a bound left out.

    One split of ``val_fraction`` of the utterances (at least two where the corpus allows it,
    so that the manifold method's validation figure is cross-fitted, never in-sample) when it
    holds at least :data:`MIN_SPLIT_UTTERANCES` or when holding each utterance out in turn
    would fit the states on more than :func:`default_fit_frames` frames in all (what one
    split at the budget costs); else every training utterance is held out once (leave one
    out). A single split over ``budget`` is bounded as :func:`select_settings` says; the
    second value is then (the fit split's frames, its validation utterances) before the
    bound, else None.
    """
    utts = list(corpus.utterances)
    n = len(utts)
    n_val = min(n - 2, max(2 if n >= 4 else 1, int(round(val_fraction * n))))
    if n_val < MIN_SPLIT_UTTERANCES and (n - 1) * sum(u.n_frames for u in utts) <= default_fit_frames():
        return [([v for v in utts if v is not u], [u]) for u in utts], None
    held = set(rng.choice(n, size=n_val, replace=False).tolist())
    val = [u for i, u in enumerate(utts) if i in held]
    fit = [u for i, u in enumerate(utts) if i not in held]
    n_fit_all, n_val_all = sum(u.n_frames for u in fit), len(val)
    if n_fit_all <= budget:
        return [(fit, val)], None
    # states on a subset of whole fit utterances, scored on a proportionate subset of the validation ones
    fit = _within(fit, budget, rng, keep=1)
    val = _within(val, budget * val_fraction / (1 - val_fraction), rng, keep=min(2, len(val)))
    return [(fit, val)], (n_fit_all, n_val_all)


def select_settings(manifold, *, val_fraction=0.2, random_state=0, state_dims=STATE_DIM_CANDIDATES,
                    sigmas=SMOOTHING_CANDIDATES, neighbors=NEIGHBOR_CANDIDATES, n_states=None,
                    frames_per_state=FRAMES_PER_STATE_CANDIDATES, phones=None,
                    sliding_windows=SLIDING_WINDOW_CANDIDATES, max_fit_frames=None,
                    progress: ProgressFn = None) -> dict:
    """Choose every setting on a validation split of the training utterances and measure every method there.

    The fitted manifold's F^y stands for the training frames (the embedding saw the
    validation utterances, as it sees all training data; the *states*, their
    transitions, the learnt paths, the inverse maps and the phone models are fitted on
    the fitting part only). A corpus too small for a split of
    :data:`MIN_SPLIT_UTTERANCES` validation utterances is validated by leave one out
    instead (every training utterance held out in turn, the sums below pooled over the
    folds) where that costs no more than one split at the default frame budget. For each candidate ``state_dims``
    and K (``n_states`` if given, else one state per ``frames_per_state`` frames): the
    manifold method's share of the learnt paths per shape component
    (:func:`engine.synthesis.learnt_paths.fit_blend`) in the states and oracle protocols.
    The (dims, K) whose manifold method has the smallest states-protocol validation RMSE
    X win; at them the Viterbi path's smoothing per protocol, the phones protocol's
    lattice blend and sliding-window setting, and every method's validation RMSE X and
    LVE (the manifold method's with its weights fitted on one half of the validation
    utterances and scored on the other, and vice versa; with leave one out, on the other
    folds).

    Parameters
    ----------
    phones : bool or None
        Run the phones protocol (None: when the corpus has phone labels).
    max_fit_frames : int, float or None
        The fit split's frame budget (None: :func:`default_fit_frames`; ``math.inf``: no
        bound). A fit split over it is replaced by a random subset of its whole utterances
        within it (seeded by ``random_state``), the validation utterances by a subset within
        ``max_fit_frames * val_fraction / (1 - val_fraction)`` frames (at least two where
        there are), K is capped at :data:`engine.graph.states.MAX_DEFAULT_STATES` (the
        candidates that reach the cap merged into the first) and ``note`` says so.

    Returns
    -------
    dict
        ``state_dims``, ``frames_per_state`` (None when K was given), ``n_states``,
        ``n_neighbors``, ``sigma`` ("protocol/viterbi" -> frames), ``blend`` (protocol ->
        weights), ``sliding_window`` (context, output window, alpha), ``protocols``,
        ``validation`` (per candidate "dims/frames-per-state"), ``method_validation``
        (protocol -> method -> {"rmse_x", "lve"}), ``best`` (protocol -> method),
        ``val_ids``, ``note``.
    """
    c = manifold.corpus_
    ids = [u.id for u in c.utterances]
    budget = _check_fit_frames(max_fit_frames, frames_per_state)
    if not 0 < float(val_fraction) < 1:
        raise ValueError(f"val_fraction must be in (0, 1), got {val_fraction}; the default is 0.2")
    maxd = int(manifold.Fy_.shape[1])
    cand = [int(d) for d in state_dims if 1 <= int(d) <= maxd]
    if not cand:
        raise ValueError(f"no candidate state_dims in {list(state_dims)} fits the {maxd} dims of F^y")
    phones = has_phone_labels(c) if phones is None else bool(phones)
    if len(ids) < MIN_VALIDATION_UTTERANCES:
        return _defaults(manifold, cand, n_states, ids, phones)
    rng = np.random.default_rng(random_state)
    report(progress, "validation split", 0, 1)
    splits, bounded = _splits(c, val_fraction, rng, budget)
    folds = [_Fold(manifold, fit, val, phones) for fit, val in splits]
    Ks = [_k_candidates(len(f.Fy), len(manifold.Fy_), n_states, frames_per_state, bounded is not None)
          for f in folds]
    table, best_key, best_err, best = {}, None, np.inf, None
    steps = len(cand) * len(Ks[0]) + 2
    for j, d in enumerate(cand):
        k, k_err = _select_neighbors(folds, d, neighbors)
        for i, fps in enumerate(Ks[0]):
            report(progress, "validation", j * len(Ks[0]) + i, steps)
            sms = [StateModel(state_dims=d, n_states=K[fps], n_neighbors=k, random_state=random_state).fit(
                f.Fy, f.Fx, f.Fxv, f.bounds, phones=f.mids) for f, K in zip(folds, Ks)]
            acc = _accumulate(sms, folds, ("states", "oracle"))
            fitted = {p: fit_blend(acc[p]) for p in acc}
            frames = fitted["states"]["frames"]
            row = {f"{p}/{name}": float(np.sqrt(sum(v) / frames)) for p in fitted
                   for name, v in (("manifold", fitted[p]["sq_error"]), ("sv-hermite", fitted[p]["sq_bases"][0]))}
            table[f"{d}/{fps}"] = {"dims": d, "frames_per_state": fps,
                                   "K": int(round(np.mean([sm.n_states_ for sm in sms]))), "k": k, "k_errors": k_err,
                                   "rmse_x": row}
            if row["states/manifold"] < best_err:
                best_key, best_err, best = f"{d}/{fps}", row["states/manifold"], (sms, acc, fitted)
    assert best is not None and best_key is not None  # the grid is never empty
    sms, acc, fitted = best
    t = table[best_key]
    protos = ("states", "oracle", "phones") if phones else ("states", "oracle")
    report(progress, "validation", steps - 2, steps)
    # the Viterbi path's smoothing per protocol, at the chosen states
    lattice = [[sm.phone_states(tg.frames, tg.labels) for tg in f.V.targets] for sm, f in zip(sms, folds)] \
        if phones else None
    sigma = _viterbi_sigmas(sms, folds, sigmas, protos, lattice)
    settings = {"state_dims": t["dims"], "frames_per_state": t["frames_per_state"], "n_neighbors": t["k"],
                "sigma": {f"{p}/viterbi": s for p, s in sigma.items()}, "protocols": list(protos)}
    models = None
    if phones:
        acc["phones"] = _accumulate(sms, folds, ("phones",), lattice)["phones"]
        fitted["phones"] = fit_blend(acc["phones"])
        sw, sw_err = _choose_sliding_window(manifold, folds, sliding_windows)
        settings["sliding_window"], settings["sliding_window_errors"] = sw, sw_err
        models = []
        for f in folds:
            fit_ids = {u.id for u in f.fit}  # without a bound: exactly the validation utterances
            models.append(PhoneModels.fit(manifold, f.fit, sliding=sw, exclude=[i for i in ids if i not in fit_ids]))
    settings["blend"] = fitted
    report(progress, "validation", steps - 1, steps)
    settings["method_validation"] = _method_validation(sms, settings, folds, acc, models, protos, lattice, progress)
    settings["best"] = {p: min(r, key=lambda name: r[name]["rmse_x"]) for p, r in settings["method_validation"].items()}
    fps = t["frames_per_state"]
    K = n_states if fps is None else max(2, int(round(len(manifold.Fy_) / fps)))
    pos = {u.id: i for i, u in enumerate(c.utterances)}
    val_ids = sorted(pos[u.id] for f in folds for u in f.V.utts)
    if len(folds) > 1:
        note = (f"chosen by leave one out over the {len(ids)} training utterances (each held out from the states "
                f"in turn; a split would hold fewer than {MIN_SPLIT_UTTERANCES})")
    else:
        note = f"chosen on {len(val_ids)} of {len(ids)} training utterances held out from the states"
    if bounded:
        f, (n_fit_all, n_val_all) = folds[0], bounded
        note += (f"; the fit split ({n_fit_all} frames) is over the {budget:.0f}-frame budget: the states were fitted "
                 f"on a random subset of {len(f.fit)} whole fit utterances ({len(f.Fy)} frames) and scored on "
                 f"{len(f.V.utts)} of the {n_val_all} validation utterances")
        if fps is not None:  # an n_states given is the caller's
            K = min(K, MAX_DEFAULT_STATES)
            note += f"; K at most {MAX_DEFAULT_STATES} (the state graph's cap)"
    settings.update(n_states=K, validation=table, val_ids=[ids[i] for i in val_ids], note=note)
    report(progress, "validation", steps, steps)
    return settings


def _k_candidates(n_fit, n_all, n_states, frames_per_state, bounded):
    """K per candidate (frames per state, or None when ``n_states`` is given) for ``n_fit`` fitting frames."""
    if n_states is not None:
        return {None: max(2, int(round(n_states * n_fit / n_all)))}
    Ks = {int(f): max(2, min(n_fit, int(round(n_fit / float(f))))) for f in frames_per_state}
    if not bounded:
        return Ks
    capped = {}  # at most the state graph's cap; candidates that reach it are one candidate
    for f, K in Ks.items():
        if min(K, MAX_DEFAULT_STATES) not in capped.values():
            capped[f] = min(K, MAX_DEFAULT_STATES)
    return capped


def _select_neighbors(folds, d, neighbors):
    """k of the local-linear inverse with the smallest validation error pooled over the folds, and the errors."""
    if len(folds) == 1:
        f = folds[0]
        return select_neighbors(f.Fy, f.Fx, f.Fy_val, f.Fx_val, n_dims=d, candidates=neighbors)
    sq, n = {}, 0
    for f in folds:
        _, err = select_neighbors(f.Fy, f.Fx, f.Fy_val, f.Fx_val, n_dims=d, candidates=neighbors)
        for k, e in err.items():
            sq.setdefault(k, []).append(e ** 2 * len(f.Fy_val))
        n += len(f.Fy_val)
    errors = {k: float(np.sqrt(sum(v) / n)) for k, v in sq.items() if len(v) == len(folds)}
    return min(errors, key=errors.get), errors


def _utterances(sms, folds):
    """Every validation utterance, fold by fold: (fold index j, index i in the fold, the fold's state model,
    its :class:`_Val`, the targets, the scored span (lo, hi), the true X (n, m), the target states)."""
    for j, (sm, fold) in enumerate(zip(sms, folds)):
        V = fold.V
        for i, tg in enumerate(V.targets):
            lo, hi = V.span(i)
            yield j, i, sm, V, tg, lo, hi, V.X[i], sm.predict(manifold_y(V.m, V.utts[i])[tg.frames])


def _accumulate(sms, folds, protos, lattice=None):
    """Per protocol, per validation utterance (fold by fold): the blend sums of the bases, pooled paths and truth."""
    out = {p: [] for p in protos}
    for j, i, sm, _V, tg, lo, hi, X, st in _utterances(sms, folds):
        f, n = tg.frames, tg.n_frames
        for p in protos:
            s = lattice[j][i] if p == "phones" else st
            xt = X[f] if p == "oracle" else None
            B = sm.bases_x(f, s, n, xt)
            P = sm.pooled_x(f, s, n, xt)
            a = BlendAccumulator(len(BASES), len(NEIGHBOR_STEPS), X.shape[1])
            a.add(B[:, lo:hi], P[:, lo:hi], X[lo:hi])
            out[p].append(a)
    return out


def manifold_y(manifold, u):
    """F^y (n, k) of a training utterance of the manifold."""
    return np.asarray(manifold.Fy_[u.start:u.stop], dtype=np.float64)


def _viterbi_sigmas(sms, folds, sigmas, protos, lattice):
    sq = {(p, s): 0.0 for p in protos for s in sigmas}
    for j, i, sm, _V, tg, lo, hi, X, st in _utterances(sms, folds):
        f, n = tg.frames, tg.n_frames
        paths = {}
        if "states" in protos:
            paths["states"] = paths["oracle"] = sm.path(f, st, n)[0]
        if "phones" in protos:
            paths["phones"] = sm.path(f, lattice[j][i], n)[0]
        for p in protos:
            for s in sigmas:
                Xh = sm.path_x(paths[p], how="state-mean", sigma=s)
                if p == "oracle":
                    Xh = anchor(Xh, f, X[f])
                sq[(p, s)] += float(((Xh - X)[lo:hi] ** 2).sum())
    return {p: float(min(sigmas, key=lambda s: sq[(p, s)])) for p in protos}


def _choose_sliding_window(manifold, folds, candidates):
    from engine.synthesis.sliding_window import SlidingWindowRegressor
    from engine.synthesis.trajectory import phone_sequences

    rate = manifold.corpus_.rate
    err = {}
    for ctx, ow, alpha in candidates:
        sq = n = 0
        for fold in folds:
            sw = SlidingWindowRegressor(context=int(ctx), output_window=int(ow), alpha=float(alpha)).fit(
                phone_sequences(fold.fit, manifold.Fx_), rate)
            V = fold.V
            for i, tg in enumerate(V.targets):
                lo, hi = V.span(i)
                Xh = sw.predict(tg.phones, tg.n_frames, tg.rate)
                sq += float(((Xh - V.X[i])[lo:hi] ** 2).sum())
                n += hi - lo
        err[f"{ctx}/{ow}/{alpha:g}"] = float(np.sqrt(sq / max(n, 1)))
    best = min(err, key=err.get)
    ctx, ow, alpha = best.split("/")
    return (int(ctx), int(ow), float(alpha)), err


def _method_validation(sms, settings, folds, acc, models, protos, lattice, progress=None):
    """Validation RMSE X and LVE of every method at the chosen settings; the manifold's cross-fitted.

    Each validation utterance's manifold trajectory takes the blend weights fitted on the
    utterances of the other folds (one split: of the other half of its utterances). Reports
    stage ``"validating every method"``, one count per validation utterance.
    """
    owner = [j for j, f in enumerate(folds) for _ in f.V.utts]
    n = len(owner)
    group = owner if len(folds) > 1 else [i % 2 for i in range(n)]
    cross = {}
    for p in protos:
        w = {g: fit_blend([acc[p][i] for i in range(n) if group[i] != g]) if n > 1 else settings["blend"][p]
             for g in set(group)}
        cross[p] = [w[g] for g in group]
    sums = {}
    mean_x = np.asarray(folds[0].V.m.Fx_, np.float64).mean(axis=0)
    for flat, (j, i, sm, V, tg, lo, hi, Xv, st) in enumerate(_utterances(sms, folds)):
        report(progress, "validating every method", flat, n)
        trajs, _ = trajectories(sm, settings, tg, st, mean_x, phone_models=None if models is None else models[j],
                                protocols=protos, lattice_states=None if lattice is None else lattice[j][i])
        for p in protos:
            if n > 1:  # the manifold method scored with weights fitted on the other utterances
                s = lattice[j][i] if p == "phones" else st
                xt = Xv[tg.frames] if p == "oracle" else None
                trajs[p]["manifold"] = sm.learnt_x(tg.frames, s, tg.n_frames, cross[p][flat], x_targets=xt)
            for name, X in trajs[p].items():
                sc = scores(V.m, X, V.F[i], lo, hi)
                a = sums.setdefault(p, {}).setdefault(name, [0.0, 0.0, 0])
                a[0] += sc["sq_x"]
                a[1] += sc["lve_sum"]
                a[2] += sc["frames"]
    return {p: {name: {"rmse_x": float(np.sqrt(a[0] / a[2])), "lve": a[1] / a[2]} for name, a in r.items()}
            for p, r in sums.items()}

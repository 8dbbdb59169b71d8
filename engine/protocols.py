"""Held-out synthesis under two protocols in which every method gets the same information.

Whole utterances are held out; everything is fitted on the rest. The targets of a
held-out utterance are its phone mid-point frames (collisions merged). Two protocols:

``states`` -- every method gets only the *target states* (the state of each target
    frame's out-of-sample F^y, in ``state_dims`` dims):
    ``manifold``      Viterbi path between the states, X = each state's mean F^x,
                      smoothed (sigma validated);
    ``manifold-ll``   the same path's state centroids smoothed in Y, X through the
                      local-linear inverse (k validated);
    ``linear``, ``pchip`` through the target states' mean F^x;
    ``hermite``       cubic Hermite through the states' mean F^x with the states' mean
                      velocity F^x'.
``oracle`` -- every method gets the oracle F^x at the targets *and* the target state:
    ``manifold``, ``manifold-ll``  the paths above anchored to the oracle X at the
                      targets (:func:`engine.statepaths.anchor`);
    ``linear``, ``pchip`` through the oracle X; ``hermite`` through the oracle X with
                      each target state's mean velocity;
    ``unitselection`` concatenative unit selection from the phones and their times.

Both tables add ``mean-frame``: the training corpus's mean frame, held throughout
(any method that does not beat it has learnt nothing about this talker).

Scores over the frames from the first to the last target, every method alike:
``rmse_x`` (Euclidean error in X, RMS over frames), ``rmse_y`` (the first
:data:`Y_DIMS` dims of Y; *every* trajectory, the manifold's included, projected
out-of-sample through the same fitted pipeline, :func:`engine.evaluation.project_x`,
against the held-out utterance's own projection), and ``lve`` (lip-vertex error: per
frame the largest Euclidean error over the points, in the corpus's units, averaged over
frames). Per-utterance differences to ``manifold`` are summarised with a bootstrap CI
and a sign test (:mod:`engine.paired`).

Settings (``state_dims``, the number of states K, the smoothing of each manifold method
per protocol, k of the local-linear inverse) are chosen on a validation split of the *training* utterances
(:func:`select_settings`), never on held-out results.
"""
from __future__ import annotations

import numpy as np

from engine.inverse_local import NEIGHBOR_CANDIDATES, select_neighbors
from engine.progress import ProgressFn, report
from engine.statepaths import StateModel, anchor, interpolate_targets

__all__ = ["PROTOCOLS", "PROTOCOL_METHODS", "STATE_DIM_CANDIDATES", "FRAMES_PER_STATE_CANDIDATES",
           "SMOOTHING_CANDIDATES", "Y_DIMS",
           "select_settings", "evaluate_protocols"]

PROTOCOLS = ("states", "oracle")
PROTOCOL_METHODS = {
    "states": ("manifold", "manifold-ll", "linear", "pchip", "hermite", "mean-frame"),
    "oracle": ("manifold", "manifold-ll", "linear", "pchip", "hermite", "unitselection", "mean-frame"),
}
MEASURES = ("rmse_x", "rmse_y", "lve")
STATE_DIM_CANDIDATES = (3, 5, 8)
#: K candidates: one state per this many training frames (30: the state graph's default)
FRAMES_PER_STATE_CANDIDATES = (30, 15, 8)
SMOOTHING_CANDIDATES = (0.0, 1.0, 2.0, 3.0, 4.0, 6.0)
Y_DIMS = 3
_MANIFOLDS = {"manifold": "state-mean", "manifold-ll": "local-linear"}


def _slice_rows(A, utts):
    return np.concatenate([A[u.start:u.stop] for u in utts])


def _bounds(utts):
    n = np.cumsum([0] + [u.n_frames for u in utts])
    return np.column_stack([n[:-1], n[1:]])


def _mid_frames(manifold, uid, corpus=None):
    from engine.targets import targets_from_utterance

    return targets_from_utterance(manifold, uid, corpus=corpus, on_collision="merge")


def select_settings(manifold, *, val_fraction=0.2, random_state=0, state_dims=STATE_DIM_CANDIDATES,
                    sigmas=SMOOTHING_CANDIDATES, neighbors=NEIGHBOR_CANDIDATES, n_states=None,
                    frames_per_state=FRAMES_PER_STATE_CANDIDATES, progress: ProgressFn = None) -> dict:
    """Choose ``state_dims``, K, smoothing and k on a validation split of the training utterances.

    The fitted manifold's F^y stands for the training frames (the embedding saw the
    validation utterances, as it sees all training data; the *states*, their
    transitions and the inverse maps are fitted on the fitting part only). For each
    candidate ``state_dims``: k of the local-linear inverse by reconstruction of the
    validation frames' X from their F^y; then for each K (``n_states`` if given, else
    one state per ``frames_per_state`` frames) the states-protocol and oracle-protocol
    synthesis of every validation utterance. The (dims, K) with the smallest validation
    RMSE in X of ``manifold`` (states protocol, best sigma) win, and each manifold
    method's sigma per protocol is the best at those.

    Returns
    -------
    dict
        ``state_dims``, ``frames_per_state`` (None when K was given), ``n_states`` (K for
        the whole training set, or None for the default), ``n_neighbors``, ``sigma``
        (dict "protocol/method" -> frames), ``validation`` (errors per candidate, keyed
        "dims/frames-per-state"), ``val_ids``, ``note``.
    """
    c = manifold.corpus_
    ids = [u.id for u in c.utterances]
    maxd = int(manifold.Fy_.shape[1])
    cand = [int(d) for d in state_dims if 1 <= int(d) <= maxd]
    if not cand:
        raise ValueError(f"no candidate state_dims in {list(state_dims)} fits the {maxd} dims of F^y")
    if len(ids) < 3:
        d = min(cand, key=lambda x: abs(x - 5))
        return {"state_dims": d, "n_neighbors": 40, "n_states": n_states, "frames_per_state": None,
                "sigma": {f"{p}/{m}": 2.0 for p in PROTOCOLS for m in _MANIFOLDS}, "validation": {}, "val_ids": [],
                "note": f"only {len(ids)} training utterance(s): no validation split; fixed defaults "
                        f"(state_dims {d}, default K, k 40, sigma 2 frames)"}
    rng = np.random.default_rng(random_state)
    n_val = min(len(ids) - 2, max(1, int(round(val_fraction * len(ids)))))
    val_ids = sorted(rng.choice(len(ids), size=n_val, replace=False).tolist())
    val = [c.utterances[i] for i in val_ids]
    fit = [u for i, u in enumerate(c.utterances) if i not in set(val_ids)]
    Fy_fit, Fx_fit, Fxv_fit = (_slice_rows(A, fit) for A in (manifold.Fy_, manifold.Fx_, manifold.Fxv_))
    b_fit = _bounds(fit)
    Fy_val, Fx_val = _slice_rows(manifold.Fy_, val), _slice_rows(manifold.Fx_, val).astype(np.float64)
    targets = [_mid_frames(manifold, u.id).frames for u in val]
    N_fit = len(Fy_fit)
    if n_states is not None:
        Ks = {None: max(2, int(round(n_states * N_fit / len(manifold.Fy_))))}
    else:
        Ks = {int(f): max(2, min(N_fit, int(round(N_fit / float(f))))) for f in frames_per_state}
    table = {}
    steps = len(cand) * len(Ks)
    for j, d in enumerate(cand):
        k, k_err = select_neighbors(Fy_fit, Fx_fit, Fy_val, Fx_val, n_dims=d, candidates=neighbors)
        for i, (fps, K) in enumerate(Ks.items()):
            report(progress, "validation", j * len(Ks) + i, steps)
            sm = StateModel(state_dims=d, n_states=K, n_neighbors=k, random_state=random_state).fit(
                Fy_fit, Fx_fit, Fxv_fit, b_fit)
            sq = {(p, m, s): 0.0 for p in PROTOCOLS for m in _MANIFOLDS for s in sigmas}
            n = 0
            for u, f in zip(val, targets):
                Yu, Xu = manifold.Fy_[u.start:u.stop], manifold.Fx_[u.start:u.stop].astype(np.float64)
                path, _ = sm.path(f, sm.predict(Yu[f]), u.n_frames)
                lo, hi = int(f[0]), int(f[-1]) + 1
                n += hi - lo
                for m, how in _MANIFOLDS.items():
                    for s in sigmas:
                        X = sm.path_x(path, how=how, sigma=s)
                        sq[("states", m, s)] += float(((X - Xu)[lo:hi] ** 2).sum())
                        sq[("oracle", m, s)] += float(((anchor(X, f, Xu[f]) - Xu)[lo:hi] ** 2).sum())
            table[f"{d}/{fps}"] = {"dims": d, "frames_per_state": fps, "K": sm.n_states_, "k": k, "k_errors": k_err,
                                   "rmse_x": {f"{p}/{m}/{s:g}": float(np.sqrt(v / max(n, 1)))
                                              for (p, m, s), v in sq.items()}}
    report(progress, "validation", steps, steps)

    def best_sigma(key, p, m):
        r = table[key]["rmse_x"]
        return min(sigmas, key=lambda s: r[f"{p}/{m}/{s:g}"])

    best = min(table, key=lambda key: table[key]["rmse_x"][f"states/manifold/{best_sigma(key, 'states', 'manifold'):g}"])
    t = table[best]
    fps = t["frames_per_state"]
    K = n_states if fps is None else max(2, int(round(len(manifold.Fy_) / fps)))
    return {"state_dims": t["dims"], "frames_per_state": fps, "n_states": K, "n_neighbors": t["k"],
            "sigma": {f"{p}/{m}": float(best_sigma(best, p, m)) for p in PROTOCOLS for m in _MANIFOLDS},
            "validation": table, "val_ids": [ids[i] for i in val_ids],
            "note": f"chosen on {len(val_ids)} of {len(ids)} training utterances held out from the states"}


def _score(manifold, X, F, Y_true, lo, hi):
    """Per-frame errors over [lo, hi): X, Y (first Y_DIMS), LVE."""
    from engine.evaluation import project_x

    dims = manifold.corpus_.dims
    Xt = manifold.shape_.transform(F[lo:hi]).astype(np.float64)
    ex = np.linalg.norm(X[lo:hi] - Xt, axis=1)
    Yh = project_x(manifold, X)[lo:hi, :Y_DIMS].astype(np.float64)
    ey = np.linalg.norm(Yh - Y_true[lo:hi, :Y_DIMS], axis=1)
    n = hi - lo
    Fh = manifold.shape_.inverse_transform(X[lo:hi].astype(np.float32)).astype(np.float64).reshape(n, -1, dims)
    ep = np.linalg.norm(Fh - F[lo:hi].astype(np.float64).reshape(n, -1, dims), axis=2)
    return ex, ey, ep.max(axis=1)


def _trajectories(manifold, sm, settings, tg, Y, mean_x, us):
    """Every method's X (n, m) per protocol for one held-out utterance."""
    f = tg.frames
    n = tg.n_frames
    d = int(settings["state_dims"])
    st = sm.predict(Y[f, :d])
    Xo = np.array([t.x for t in tg.targets], dtype=np.float64)
    Xs, Vs = sm.inverse_.means_[st], sm.inverse_.velocity_means_[st]
    path, missed = sm.path(f, st, n)
    out = {"states": {}, "oracle": {}}
    for m, how in _MANIFOLDS.items():
        out["states"][m] = sm.path_x(path, how=how, sigma=settings["sigma"][f"states/{m}"])
        out["oracle"][m] = anchor(sm.path_x(path, how=how, sigma=settings["sigma"][f"oracle/{m}"]), f, Xo)
    for kind in ("linear", "pchip", "hermite"):
        out["states"][kind] = interpolate_targets(kind, f, Xs, n, Vs)
        out["oracle"][kind] = interpolate_targets(kind, f, Xo, n, Vs)
    out["oracle"]["unitselection"] = np.asarray(us.synthesize(tg.phones_only()).Fx, dtype=np.float64)
    for p in PROTOCOLS:
        out[p]["mean-frame"] = np.repeat(mean_x[None], n, axis=0)
    return out, missed


def evaluate_protocols(corpus, *, test_fraction=0.1, test_ids=None, random_state=0, manifold_factory=None,
                       settings=None, settings_factory=None, n_boot=2000, inverse_table=True,
                       progress: ProgressFn = None):
    """Hold out utterances, fit on the rest, run both protocols; see the module docstring.

    Parameters
    ----------
    corpus : Corpus
    test_fraction, test_ids, random_state
        As :func:`engine.evaluation.split_utterances`.
    manifold_factory : callable(train corpus) -> fitted Manifold, optional
    settings : dict, optional
        ``state_dims``, ``n_neighbors``, ``sigma`` as returned by :func:`select_settings`
        (default: chosen by it on the training utterances).
    settings_factory : callable(fitted Manifold) -> dict, optional
        Makes the settings from the training manifold when ``settings`` is None.
    n_boot : int
        Bootstrap resamples of the paired comparisons.
    inverse_table : bool
        Also reconstruct the held-out frames' X from their own F^y with each inverse map
        (the paper's 3-D Delaunay, local-linear in 3 and ``state_dims`` dims, state means).

    Returns
    -------
    ProtocolResult
    """
    from engine.evaluation import fit_on_training_split
    from engine.protocol_report import ProtocolResult
    from engine.unitselection import UnitSelectionSynthesizer

    train_ids, test, train, manifold = fit_on_training_split(
        corpus, test_fraction=test_fraction, test_ids=test_ids, random_state=random_state,
        manifold_factory=manifold_factory, progress=progress)
    if settings is None:
        settings = (settings_factory(manifold) if settings_factory is not None
                    else select_settings(manifold, random_state=random_state, progress=progress))
    d = int(settings["state_dims"])
    sm = StateModel(state_dims=d, n_states=settings.get("n_states"), n_neighbors=int(settings["n_neighbors"]),
                    random_state=random_state).fit(
        manifold.Fy_, manifold.Fx_, manifold.Fxv_, manifold.corpus_.bounds)
    us = UnitSelectionSynthesizer().fit(manifold)
    mean_x = np.asarray(manifold.Fx_, dtype=np.float64).mean(axis=0)
    per, failures, missed, inv = [], [], 0, {}
    for j, uid in enumerate(test):
        report(progress, "protocols", j, len(test))
        u = corpus.utterance(uid)
        F = corpus.frames[u.start:u.stop]
        try:
            tg = _mid_frames(manifold, uid, corpus)
            Y = manifold.project(F).astype(np.float64)
            trajs, miss = _trajectories(manifold, sm, settings, tg, Y, mean_x, us)
        except ValueError as exc:
            failures.append(f"{uid}: {exc}")
            continue
        missed += miss
        lo, hi = int(tg.frames[0]), int(tg.frames[-1]) + 1
        for p, methods in trajs.items():
            for m, X in methods.items():
                ex, ey, lv = _score(manifold, X, F, Y, lo, hi)
                per.append({"protocol": p, "method": m, "utterance": uid, "frames": hi - lo,
                            "sq_x": float((ex ** 2).sum()), "sq_y": float((ey ** 2).sum()), "lve_sum": float(lv.sum()),
                            "rmse_x": float(np.sqrt((ex ** 2).mean())), "rmse_y": float(np.sqrt((ey ** 2).mean())),
                            "lve": float(lv.mean())})
        if inverse_table:
            _inverse_errors(inv, manifold, sm, F, Y)
    report(progress, "protocols", len(test), len(test))
    return ProtocolResult.build(per, corpus=corpus.name, test_ids=test, train_ids=train_ids,
                                n_train_frames=train.n_frames, settings=settings, failures=failures,
                                missed_gaps=missed, inverse=inv, n_states=sm.n_states_,
                                state_warnings=sm.connectivity_warnings_, n_boot=n_boot, random_state=random_state,
                                manifold=manifold)


def _inverse_errors(acc, manifold, sm, F, Y):
    """Accumulate squared X error and LVE of each inverse map on one held-out utterance's own F^y."""
    from engine.inverse_local import LocalLinearInverse

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

"""Which synthesis method a corpus's own validation split measures best, cached with its manifold.

:func:`choose_methods` runs :func:`engine.evaluation.protocols.select_settings` on a fitted manifold
(every utterance of its corpus counts as training: a fifth of them is the validation
split, the rest fits the states, the learnt paths and the phone models). The result --
the validated settings, every method's validation RMSE X and LVE per protocol, and the
best method per protocol -- is kept in two places:

* in the manifold file: :func:`fit_choice` (``lipspace build`` runs it after the fit) stores
  it as ``Manifold.synthesis_choice_`` with the synthesiser's state centres on every frame
  (``synthesis_states_``) and the phone models measured best, fitted on every utterance
  (``synthesis_models_``: the dominance functions take minutes to fit on a large corpus), so
  the first synthesis from a built file runs no validation, no K-means and no model fit;
  all of it is used while the code that measured it (:func:`choice_code`) is the code
  running;
* in the cache folder, as JSON under a key made from the manifold's data and that code
  (:func:`choice_path`): a manifold without a stored choice (a file written before builds
  stored it, a corpus fitted in the window) is measured once, at its first synthesis.

Which protocol a synthesis is in follows from its targets (:func:`target_protocol`): the
true X and a state at every target (a corpus utterance's own targets) is ``oracle``;
states or F^y points (clicked states) is ``states``; phones and times only (text, a
phone string, a TextGrid) is ``phones``. The method used by default is the one measured
best in that protocol (:func:`best_method`), named with its margin (:func:`describe`).
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

from engine.synthesis.stored_choice import (
    CHOICE_MODULES,
    STORED_MODELS,
    choice_code,
    phone_model,
    stored_choice,
    stored_model,
    stored_states,
)

__all__ = ["BEST", "choose_methods", "fit_choice", "stored_choice", "stored_states", "stored_model", "phone_model",
           "STORED_MODELS", "choice_code", "load_choice", "choice_path", "manifold_fingerprint", "target_protocol",
           "best_method", "describe", "CHOICE_MODULES"]

#: the method name that asks for the method measured best on validation
BEST = "best"
#: settings kept in the cache (the rest of select_settings' answer is diagnostics)
_KEPT = ("state_dims", "frames_per_state", "n_states", "n_neighbors", "sigma", "blend", "sliding_window",
         "protocols", "method_validation", "best", "val_ids", "note")


def manifold_fingerprint(manifold) -> str:
    """A short hash of what the validation sees of a fitted manifold: F^x, F^y, utterances, phones."""
    h = hashlib.sha256()
    for A in (manifold.Fx_, manifold.Fy_):
        A = np.ascontiguousarray(A)
        h.update(str(A.shape).encode())
        h.update(A[:: max(1, A.shape[0] // 4096)].tobytes())
        h.update(np.asarray(A.sum(axis=0, dtype=np.float64)).tobytes())
    c = manifold.corpus_
    h.update(json.dumps([[u.id, u.n_frames, [(p.label, round(p.start, 6), round(p.end, 6)) for p in u.phones]]
                         for u in c.utterances]).encode())
    return h.hexdigest()[:16]


def choice_path(manifold, cache_dir=None) -> Path:
    """Where the choice for ``manifold`` is cached: ``<cache>/method-choice/<data key>-<code key>.json``."""
    if cache_dir is None:
        from engine.files.userdirs import user_dir

        cache_dir = user_dir("cache", "LIPSPACE_CACHE_DIR")
    return Path(cache_dir) / "method-choice" / f"{manifold_fingerprint(manifold)}-{choice_code()}.json"


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, np.generic):
        return x.item()
    return x


def load_choice(manifold, cache_dir=None) -> dict | None:
    """The cached choice for ``manifold``, or None (not measured yet by this code, or unreadable)."""
    from engine.files.bounded import parse_json, read_bounded

    p = choice_path(manifold, cache_dir)
    try:  # a regular file of a few kB: a FIFO or a huge file at its name is not a choice
        d = parse_json(read_bounded(p, limit=16 * 2**20), source=p)
    except (OSError, ValueError):
        return None
    return d if isinstance(d, dict) and "best" in d and "blend" in d else None


def _measure(manifold, progress):
    from engine.synthesis.validation import select_settings

    s = select_settings(manifold, progress=progress)
    out = _jsonable({k: s[k] for k in _KEPT if k in s})
    out["code"] = choice_code()
    return out


def fit_choice(manifold, *, progress=None) -> dict:
    """Measure the choice on ``manifold``'s corpus and keep it on the manifold, for its file.

    Sets ``manifold.synthesis_choice_`` (what :func:`choose_methods` returns) and
    ``manifold.synthesis_states_``: the centres of the state model the synthesisers fit at the
    chosen settings (``state_dims``, ``n_states``) on every frame, the K-means of the
    synthesis step done once here. :meth:`engine.manifold.model.Manifold.save` stores both.

    Parameters
    ----------
    manifold : engine.manifold.model.Manifold
        Fitted.
    progress : callable(stage, done, total), optional
        Sees the validation's stages, then ``"synthesis states"``; may raise
        :class:`engine.progress.Cancelled` (the manifold is left without a choice).

    Returns
    -------
    dict
        The choice (JSON-able).
    """
    import warnings

    from engine.graph.states import StateGraph
    from engine.progress import report

    choice = _measure(manifold, progress)
    report(progress, "synthesis states", 0, 1)
    with warnings.catch_warnings(record=True):  # as the synthesiser's state model: its connectivity is kept there
        warnings.simplefilter("always")
        graph = StateGraph(n_states=choice.get("n_states"), n_dims=int(choice["state_dims"])).fit(
            manifold.Fy_, manifold.corpus_.bounds)
    report(progress, "synthesis states", 1, 1)
    from engine.files.persist import dump_estimator
    from engine.synthesis.trajectory import phone_sequences

    models = {}
    best = sorted({m for m in (choice.get("best") or {}).values() if m in STORED_MODELS})
    for k, method in enumerate(best):  # as make_synthesizer fits it: on every utterance with phones
        report(progress, "synthesis models", k, len(best))
        c = manifold.corpus_
        models.update(dump_estimator(phone_model(method, choice).fit(phone_sequences(c.utterances, manifold.Fx_),
                                                                     c.rate), method))
    report(progress, "synthesis models", len(best), len(best))
    manifold.synthesis_choice_, manifold.synthesis_states_ = choice, graph.centroids_
    manifold.synthesis_models_ = models
    return choice


def choose_methods(manifold, *, cache_dir=None, use_cache=True, progress=None) -> dict:
    """The validated settings and the best method per protocol of ``manifold``'s corpus.

    The one the manifold's file stores (:func:`stored_choice`), else the cached one, else
    measured now (:func:`engine.synthesis.validation.select_settings`) and cached.
    ``use_cache=False`` measures it in any case.

    Returns
    -------
    dict
        The settings of :func:`engine.evaluation.protocols.select_settings` (``best``,
        ``method_validation``, ``blend``, ``state_dims``, ...), JSON-able.
    """
    if use_cache:
        hit = stored_choice(manifold) or load_choice(manifold, cache_dir)
        if hit is not None:
            return hit
    from engine.files.atomic import atomic_write

    out = _measure(manifold, progress)
    p = choice_path(manifold, cache_dir)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        with atomic_write(p) as tmp:
            Path(tmp).write_text(json.dumps(out, indent=1), encoding="utf-8")
        from engine.files.ownership import mark

        mark(p, p.parent.parent)  # Lipspace's own: 'lipspace cache --clear' may delete it
    except OSError:
        pass  # a read-only cache: the choice is recomputed next time, nothing else is lost
    return out


def target_protocol(targets) -> str:
    """The protocol a synthesis from ``targets`` is in: ``"oracle"``, ``"states"`` or ``"phones"``."""
    ts = targets.targets
    has_state = [t.state is not None or t.y is not None for t in ts]
    if ts and all(has_state) and all(t.x is not None for t in ts):
        return "oracle"
    if any(has_state):
        return "states"
    return "phones"


def best_method(choice, protocol) -> str:
    """The method measured best on validation in ``protocol`` (``"manifold"`` when nothing was measured)."""
    return ((choice or {}).get("best") or {}).get(protocol, "manifold")


def describe(choice, protocol, method) -> str:
    """``"method: sv-hermite, best on validation (states protocol: RMSE X 12.1; manifold 12.4, 2 % behind)"``."""
    val = ((choice or {}).get("method_validation") or {}).get(protocol)
    if not val or method not in val:
        note = (choice or {}).get("note") or "no validation split"
        return f"method: {method} ({protocol} protocol; not measured on validation: {note})"
    r = val[method]["rmse_x"]
    text = f"method: {method}, best on validation ({protocol} protocol: RMSE X {r:.4g}"
    man = val.get("manifold")
    if method != "manifold" and man is not None:
        text += f"; manifold {man['rmse_x']:.4g}, {100 * (man['rmse_x'] - r) / r:.0f} % behind"
    others = sorted((v["rmse_x"], k) for k, v in val.items() if k != method)
    if method == "manifold" and others:
        text += f"; next {others[0][1]} {others[0][0]:.4g}"
    return text + ")"

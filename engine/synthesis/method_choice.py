"""Which synthesis method a corpus's own validation split measures best, cached with its manifold.

:func:`choose_methods` runs :func:`engine.evaluation.protocols.select_settings` on a fitted manifold
(every utterance of its corpus counts as training: a fifth of them is the validation
split, the rest fits the states, the learnt paths and the phone models). The result --
the validated settings, every method's validation RMSE X and LVE per protocol, and the
best method per protocol -- is written as JSON into the cache folder under a key made
from the manifold's data and the code that measured it (:func:`choice_path`), so the
explorer and ``lipspace synthesize`` measure a corpus once.

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

__all__ = ["BEST", "choose_methods", "load_choice", "choice_path", "manifold_fingerprint", "target_protocol",
           "best_method", "describe", "CHOICE_MODULES"]

#: the method name that asks for the method measured best on validation
BEST = "best"
#: modules whose code decides the choice (part of the cache key)
CHOICE_MODULES = ("engine.synthesis.validation", "engine.synthesis.protocol_methods", "engine.synthesis.learnt_paths", "engine.synthesis.statepaths",
                  "engine.synthesis.dominance", "engine.synthesis.sliding_window", "engine.synthesis.unitselection", "engine.graph.states",
                  "engine.synthesis.viterbi", "engine.manifold.inverse_local", "engine.synthesis.method_choice")
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
    from engine.files.persist import source_fingerprint

    if cache_dir is None:
        from engine.files.userdirs import user_dir

        cache_dir = user_dir("cache", "LIPSPACE_CACHE_DIR")
    return Path(cache_dir) / "method-choice" / f"{manifold_fingerprint(manifold)}-{source_fingerprint(CHOICE_MODULES)}.json"


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


def choose_methods(manifold, *, cache_dir=None, use_cache=True, progress=None) -> dict:
    """The validated settings and the best method per protocol of ``manifold``'s corpus (cached).

    Returns
    -------
    dict
        The settings of :func:`engine.evaluation.protocols.select_settings` (``best``,
        ``method_validation``, ``blend``, ``state_dims``, ...), JSON-able.
    """
    if use_cache:
        hit = load_choice(manifold, cache_dir)
        if hit is not None:
            return hit
    from engine.files.atomic import atomic_write
    from engine.synthesis.validation import select_settings

    s = select_settings(manifold, progress=progress)
    out = _jsonable({k: s[k] for k in _KEPT if k in s})
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

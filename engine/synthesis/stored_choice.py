"""What a manifold file keeps of the synthesis choice, read back for the synthesisers.

:func:`engine.synthesis.method_choice.fit_choice` (run by ``lipspace build``) stores on a manifold
the validated choice (``synthesis_choice_``), the synthesiser's state centres at the chosen
settings (``synthesis_states_``) and the phone models measured best, fitted on every utterance
(``synthesis_models_``, :data:`STORED_MODELS`). Here they are read back: each only while the
code that made it is the code running (:func:`choice_code`), the state centres only for the
choice they were fitted with, a phone model only for the parameters it was fitted with.
"""
from __future__ import annotations

import json

import numpy as np

__all__ = ["CHOICE_MODULES", "STORED_MODELS", "choice_code", "stored_choice", "stored_states", "phone_model",
           "stored_model"]

#: modules whose code decides the choice (part of the cache key)
CHOICE_MODULES = ("engine.synthesis.validation", "engine.synthesis.protocol_methods", "engine.synthesis.learnt_paths",
                  "engine.synthesis.statepaths", "engine.synthesis.dominance", "engine.synthesis.sliding_window",
                  "engine.synthesis.unitselection", "engine.graph.states", "engine.synthesis.viterbi",
                  "engine.manifold.inverse_local", "engine.synthesis.method_choice", "engine.synthesis.stored_choice",
                  "engine.synthesis.trajectory")
#: phone models a build fits on every utterance and stores when one is measured best in a protocol
STORED_MODELS = ("dominance", "sliding-window")


def choice_code() -> str:
    """A hash of the code that measures a choice (:data:`CHOICE_MODULES`): a choice measured by other
    code is measured again, never used."""
    from engine.files.persist import source_fingerprint

    return source_fingerprint(CHOICE_MODULES)


def stored_choice(manifold) -> dict | None:
    """The choice the manifold's file holds (:func:`engine.synthesis.method_choice.fit_choice`), or None:
    none stored, or measured by other code than this (:func:`choice_code`)."""
    ch = getattr(manifold, "synthesis_choice_", None)
    return ch if isinstance(ch, dict) and ch.get("code") == choice_code() else None


def stored_states(manifold, choice) -> np.ndarray | None:
    """The synthesiser's state centres (K, state_dims) stored with ``choice``, or None when ``choice`` is
    not the manifold's stored one (then the synthesiser fits its own states)."""
    states = getattr(manifold, "synthesis_states_", None)
    if states is None or choice is None or stored_choice(manifold) != choice:
        return None
    return states if states.shape[1] == int(choice["state_dims"]) else None


def phone_model(method, choice=None):
    """The unfitted phone model of ``method`` (:data:`STORED_MODELS`) with the settings the synthesisers
    give it: the sliding-window regression's validated window and penalty (``choice``), the
    dominance functions' defaults."""
    from engine.synthesis.dominance import DominanceModel
    from engine.synthesis.sliding_window import SlidingWindowRegressor

    if method == "dominance":
        return DominanceModel()
    if method == "sliding-window":
        sw = (choice or {}).get("sliding_window")
        if not sw:
            return SlidingWindowRegressor()
        ctx, ow, alpha = sw
        return SlidingWindowRegressor(context=int(ctx), output_window=int(ow), alpha=float(alpha))
    raise ValueError(f"no stored phone model for method {method!r}; those are {', '.join(STORED_MODELS)}")


#: what a stored phone model must hold (engine.files.persist.load_estimator's schema)
_MODEL_SCHEMA = {
    "dominance": {"labels_": dict(kind="strlist"), "targets_": dict(kind="array", dtype="float", shape=("K", "m")),
                  "alpha_": dict(kind="array", dtype="float", shape=("K",), low=0),
                  "theta_before_": dict(kind="array", dtype="float", shape=("K",), low=0),
                  "theta_after_": dict(kind="array", dtype="float", shape=("K",), low=0),
                  "c_": dict(kind="float", low=0)},
    "sliding-window": {"labels_": dict(kind="strlist"), "vocabulary_": dict(kind="strlist"),
                       "mean_": dict(kind="array", dtype="float", shape=("W",)),
                       "coef_": dict(kind="array", dtype="float", shape=("F", "W"), none=True),
                       "n_components_": dict(kind="int", low=1)},
}


def stored_model(manifold, method, model):
    """The phone model of ``method`` the manifold's file stores, fitted, when it was fitted with ``model``'s
    parameters by this code (:func:`stored_choice`); else None (the synthesiser fits its own).

    Raises
    ------
    ValueError
        A stored model that is damaged, naming the field.
    """
    arrays = getattr(manifold, "synthesis_models_", None) or {}
    key = f"{method}/__params__"
    if method not in STORED_MODELS or key not in arrays or stored_choice(manifold) is None:
        return None
    try:
        params = json.loads(str(np.asarray(arrays[key])[()]))
    except ValueError:
        params = None
    if params != json.loads(json.dumps(model.get_params(deep=False))):
        return None
    from engine.files.persist import load_estimator

    fitted = load_estimator(type(model), arrays, method, source="the manifold file's synthesis_models",
                            schema=_MODEL_SCHEMA[method], dims={})
    if method == "dominance" and fitted.targets_.shape[0] != len(fitted.labels_):
        raise ValueError(f"the manifold file's synthesis_models/dominance: {len(fitted.labels_)} phone labels for "
                         f"{fitted.targets_.shape[0]} targets")
    return fitted

"""Every synthesis method by name: the registry the explorer and the command line build from.

====================  ===================================================================================
``"manifold"``        :class:`engine.synthesis.state_synthesis.LearntPathSynthesizer` (the learnt paths
                      between the states, with the corpus's validated settings);
``"viterbi"``         :class:`engine.synthesis.viterbi.ManifoldSynthesizer` (the paper's path);
``"sv-hermite"``      :class:`engine.synthesis.state_synthesis.StateHermiteSynthesizer`;
``"linear"``          :class:`engine.synthesis.interpolation.InterpolationSynthesizer` (straight lines);
``"cubic"``           the same class through a cubic spline;
``"unitselection"``   :class:`engine.synthesis.unitselection.UnitSelectionSynthesizer`;
``"dominance"``       :class:`engine.synthesis.dominance.DominanceModel`,
``"sliding-window"``  :class:`engine.synthesis.sliding_window.SlidingWindowRegressor`, each behind
                      :class:`engine.synthesis.trajectory.PhoneModelSynthesizer`.
====================  ===================================================================================

It sits above every synthesis module (none imports it), so they never import each other
through it.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from engine.manifold.model import Manifold
    from engine.synthesis.trajectory import Synthesizer

__all__ = ["METHODS", "make_synthesizer"]

#: method names understood by :func:`make_synthesizer`
METHODS = ("manifold", "viterbi", "sv-hermite", "linear", "cubic", "unitselection", "dominance", "sliding-window")


def make_synthesizer(method: str, manifold: Manifold, **params: Any) -> Synthesizer:
    """A fitted synthesiser by name (:data:`METHODS`).

    ``"manifold"`` and ``"sv-hermite"`` take ``choice`` (the validated settings of
    :func:`engine.synthesis.method_choice.choose_methods`; measured and cached when not given) and
    ``progress``; the others their class's parameters.
    """
    if method in ("manifold", "sv-hermite"):
        from engine.synthesis.state_synthesis import LearntPathSynthesizer, StateHermiteSynthesizer

        cls = LearntPathSynthesizer if method == "manifold" else StateHermiteSynthesizer
        progress = params.pop("progress", None)
        return cls(**params).fit(manifold, progress=progress)
    if method == "viterbi":
        from engine.synthesis.viterbi import ManifoldSynthesizer

        return ManifoldSynthesizer(**params).fit(manifold)
    if method in ("linear", "cubic"):
        from engine.synthesis.interpolation import InterpolationSynthesizer

        return InterpolationSynthesizer(kind=method, **params).fit(manifold)
    if method == "unitselection":
        from engine.synthesis.unitselection import UnitSelectionSynthesizer

        return UnitSelectionSynthesizer(**params).fit(manifold)
    if method in ("dominance", "sliding-window"):
        from engine.synthesis.dominance import DominanceModel
        from engine.synthesis.sliding_window import SlidingWindowRegressor
        from engine.synthesis.trajectory import PhoneModelSynthesizer

        model = (DominanceModel if method == "dominance" else SlidingWindowRegressor)(**params)
        return PhoneModelSynthesizer(model=model, method=method).fit(manifold)
    raise ValueError(f"unknown synthesis method {method!r}; choose one of {', '.join(METHODS)}")

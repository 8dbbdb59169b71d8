"""Every synthesis method by name: the one registry the explorer, the command line and
:func:`make_synthesizer` read.

:data:`SYNTHESIS_METHODS` maps each method's name to a :class:`SynthesisMethod`: the class that
synthesises (as ``"module:Class"``, imported only when used), the label of the window's method
menu, a one-line description, and how :func:`make_synthesizer` fits it:

====================  ===================================================================================
``"manifold"``        :class:`engine.synthesis.state_synthesis.LearntPathSynthesizer` (the learnt paths
                      between the states, with the corpus's validated settings);
``"viterbi"``         :class:`engine.synthesis.viterbi.ViterbiSynthesizer` (the paper's path);
``"sv-hermite"``      :class:`engine.synthesis.state_synthesis.StateHermiteSynthesizer`;
``"linear"``          :class:`engine.synthesis.interpolation.InterpolationSynthesizer` (straight lines);
``"cubic"``           the same class through a cubic spline;
``"unitselection"``   :class:`engine.synthesis.unitselection.UnitSelectionSynthesizer`;
``"dominance"``       :class:`engine.synthesis.dominance.DominanceModel`,
``"sliding-window"``  :class:`engine.synthesis.sliding_window.SlidingWindowRegressor`, each behind
                      :class:`engine.synthesis.trajectory.PhoneModelSynthesizer`.
====================  ===================================================================================

It sits above every synthesis module (none imports it) and imports none of them until a method
is made, so the command line reads the names without loading the method.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:
    from engine.manifold.model import Manifold
    from engine.synthesis.trajectory import Synthesizer

__all__ = ["SynthesisMethod", "SYNTHESIS_METHODS", "METHODS", "make_synthesizer"]

#: how :func:`make_synthesizer` fits a method's class: ``"estimator"`` ``cls(**params).fit(manifold)``;
#: ``"validated"`` the same with ``progress`` passed to ``fit`` (the corpus's validated settings, ``choice``,
#: are measured there when not given); ``"interpolation"`` ``cls(kind=name, **params)``; ``"phone-model"``
#: the phone model ``cls(**params)`` behind :class:`engine.synthesis.trajectory.PhoneModelSynthesizer`
Build = Literal["estimator", "validated", "interpolation", "phone-model"]


@dataclass(frozen=True)
class SynthesisMethod:
    """One synthesis method of the registry.

    Parameters
    ----------
    target : str
        The class, ``"module:Class"`` (imported by :meth:`load`).
    label : str
        Its entry in the explorer's method menu.
    description : str
        What it does, in one line.
    build : {"estimator", "validated", "interpolation", "phone-model"}
        How :func:`make_synthesizer` fits it (:data:`Build`).
    """

    target: str
    label: str
    description: str
    build: Build = "estimator"

    def load(self) -> type:
        """The method's class, its module imported now."""
        module, _, name = self.target.partition(":")
        cls: type = getattr(importlib.import_module(module), name)
        return cls


#: method name -> :class:`SynthesisMethod`, in the order the menus list them
SYNTHESIS_METHODS: dict[str, SynthesisMethod] = {
    "manifold": SynthesisMethod("engine.synthesis.state_synthesis:LearntPathSynthesizer", "Manifold (learnt paths)",
                                "the learnt paths between the manifold's states", "validated"),
    "viterbi": SynthesisMethod("engine.synthesis.viterbi:ViterbiSynthesizer",
                               "Manifold, max-probability path (paper)",
                               "the paper's maximum-probability state path (Viterbi)"),
    "sv-hermite": SynthesisMethod("engine.synthesis.state_synthesis:StateHermiteSynthesizer",
                                  "State-velocity Hermite", "Hermite curves through the states' velocities",
                                  "validated"),
    "linear": SynthesisMethod("engine.synthesis.interpolation:InterpolationSynthesizer", "Linear interpolation (X)",
                              "straight lines between the targets' shapes", "interpolation"),
    "cubic": SynthesisMethod("engine.synthesis.interpolation:InterpolationSynthesizer", "Cubic spline (X)",
                             "a cubic spline through the targets' shapes", "interpolation"),
    "unitselection": SynthesisMethod("engine.synthesis.unitselection:UnitSelectionSynthesizer", "Unit selection",
                                     "the corpus's own phone units, joined"),
    "dominance": SynthesisMethod("engine.synthesis.dominance:DominanceModel", "Dominance (Cohen–Massaro)",
                                 "Cohen-Massaro dominance functions blending phone targets", "phone-model"),
    "sliding-window": SynthesisMethod("engine.synthesis.sliding_window:SlidingWindowRegressor",
                                      "Sliding-window regression",
                                      "a regression from a window of phones to the shape", "phone-model"),
}

#: method names understood by :func:`make_synthesizer` (the keys of :data:`SYNTHESIS_METHODS`)
METHODS = tuple(SYNTHESIS_METHODS)


def make_synthesizer(method: str, manifold: Manifold, **params: Any) -> Synthesizer:
    """A fitted synthesiser by name (:data:`METHODS`).

    ``"manifold"`` and ``"sv-hermite"`` take ``choice`` (the validated settings of
    :func:`engine.synthesis.method_choice.choose_methods`; measured and cached when not given) and
    ``progress``; the others their class's parameters.
    """
    entry = SYNTHESIS_METHODS.get(method)
    if entry is None:
        raise ValueError(f"unknown synthesis method {method!r}; choose one of {', '.join(METHODS)}")
    cls = entry.load()
    if entry.build == "validated":
        progress = params.pop("progress", None)
        out: Synthesizer = cls(**params).fit(manifold, progress=progress)
    elif entry.build == "interpolation":
        out = cls(kind=method, **params).fit(manifold)
    elif entry.build == "phone-model":
        from engine.synthesis.trajectory import PhoneModelSynthesizer

        out = PhoneModelSynthesizer(model=cls(**params), method=method).fit(manifold)
    else:
        out = cls(**params).fit(manifold)
    return out

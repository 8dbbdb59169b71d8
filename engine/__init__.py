"""Lipspace engine: the visual speech manifold, computed with numpy, scipy and scikit-learn.

The public API, by stage (each name loads its module on first use, so ``import engine``
stays as light as bare Python and ``lipspace --help`` starts fast):

==========================  ==============================================================
recordings                  :class:`Corpus`, :class:`Utterance`, :class:`PhoneInterval`,
                            :func:`read_corpus` (every foreign format), :func:`read_alignment`,
                            :func:`resample`, :func:`save_blocked` / :func:`load_blocked` (blocks)
the synthetic talker        :func:`load_synthetic`, :class:`SyntheticTalker`
the manifold                :class:`Manifold` (shape space, dynamic features, embedding,
                            tangent frames, state graph, inverse map in one estimator)
the state graph             :class:`StateGraph` (``Manifold.states_``), :func:`hemisphere`
targets                     :func:`targets_from_text`, :func:`targets_from_phones`,
                            :func:`targets_from_textgrid`, :func:`targets_from_utterance`,
                            :func:`targets_from_points`
synthesis                   :data:`METHODS`, :func:`make_synthesizer`, :class:`Trajectory`
clusters                    :class:`PhoneClusters`, :func:`clusters_of`
evaluation                  :func:`evaluate_protocols`
==========================  ==============================================================

Never imports Qt, VTK, pyvista or matplotlib (import-linter contracts in pyproject.toml).
"""
from __future__ import annotations

from engine._lazy import lazy_names

__version__ = "0.1.0"

#: public name -> the module that defines it
_WHERE = {
    **dict.fromkeys(("Corpus", "CorpusError", "CorpusWarning", "PhoneInterval", "Utterance"),
                    "engine.recordings.corpus"),
    **dict.fromkeys(("load_blocked", "save_blocked"), "engine.recordings.corpus_blocks"),
    **dict.fromkeys(("read_corpus", "read_alignment", "resample"), "engine.io"),
    "load_synthetic": "engine.talker.talker_cache",
    "SyntheticTalker": "engine.talker.synthetic_talker",
    **dict.fromkeys(("Manifold", "ManifoldFileError"), "engine.manifold.model"),
    "StateGraph": "engine.graph.states",
    **dict.fromkeys(("hemisphere", "Hemisphere"), "engine.graph.hemispheres"),
    **dict.fromkeys(("targets_from_text", "targets_from_phones", "targets_from_textgrid", "targets_from_utterance",
                     "targets_from_points", "Target", "TargetSequence"), "engine.phonetics.targets"),
    **dict.fromkeys(("METHODS", "make_synthesizer"), "engine.synthesis.methods"),
    "Trajectory": "engine.synthesis.trajectory",
    **dict.fromkeys(("PhoneClusters", "clusters_of"), "engine.manifold.clusters"),
    "evaluate_protocols": "engine.evaluation.protocols",
}
__all__ = sorted(_WHERE)
__getattr__, __dir__ = lazy_names("engine", _WHERE, globals())

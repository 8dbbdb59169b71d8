"""Lipspace engine: the visual speech manifold, computed with numpy, scipy and scikit-learn.

Never imports Qt, VTK or pyvista (checked by tests/engine/test_imports.py).
"""
from engine.corpus import Corpus, CorpusError, CorpusWarning, PhoneInterval, Utterance

__all__ = ["Corpus", "CorpusError", "CorpusWarning", "PhoneInterval", "Utterance"]
__version__ = "0.1.0"

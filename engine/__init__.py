"""Lipspace engine: the visual speech manifold, computed with numpy, scipy and scikit-learn.

Never imports Qt, VTK or pyvista (checked by tests/engine/test_imports.py). The corpus
names below load on first use, so importing a light module (``engine.progress``) does
not import numpy: ``lipspace --help`` stays near bare Python's start-up.
"""
__all__ = ["Corpus", "CorpusError", "CorpusWarning", "PhoneInterval", "Utterance"]
__version__ = "0.1.0"


def __getattr__(name):
    if name in __all__:
        from engine.recordings import corpus

        return getattr(corpus, name)
    raise AttributeError(f"module 'engine' has no attribute {name!r}")

"""Engine fixtures: the held-out synthetic talker (never used to tune the method), built once per session."""
from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def heldout_corpus():
    """The small preset of the second, independently parameterised talker (engine.talker.synthetic.HELD_OUT_TALKER)."""
    from engine.talker.synthetic import HELD_OUT_TALKER, load_synthetic

    return load_synthetic(preset="small", **HELD_OUT_TALKER)


@pytest.fixture(scope="session")
def heldout_manifold(heldout_corpus):
    from engine.manifold.model import Manifold

    return Manifold().fit(heldout_corpus)

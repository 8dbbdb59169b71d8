"""Types of the public API that ``engine/__init__.py`` loads lazily (PEP 562 ``__getattr__``).

Type checkers and editors read this stub instead of the package's ``__getattr__``: each name
as imported from the module that defines it, the same table as ``engine._WHERE``
(``tests/engine/test_public_stub.py`` keeps the two equal).
"""

from engine.evaluation.protocols import (
    evaluate_protocols as evaluate_protocols,
)
from engine.graph.hemispheres import (
    Hemisphere as Hemisphere,
)
from engine.graph.hemispheres import (
    hemisphere as hemisphere,
)
from engine.graph.states import (
    StateGraph as StateGraph,
)
from engine.io import (
    read_alignment as read_alignment,
)
from engine.io import (
    read_corpus as read_corpus,
)
from engine.io import (
    resample as resample,
)
from engine.manifold.clusters import (
    PhoneClusters as PhoneClusters,
)
from engine.manifold.clusters import (
    clusters_of as clusters_of,
)
from engine.manifold.model import (
    Manifold as Manifold,
)
from engine.manifold.model import (
    ManifoldFileError as ManifoldFileError,
)
from engine.phonetics.targets import (
    Target as Target,
)
from engine.phonetics.targets import (
    TargetSequence as TargetSequence,
)
from engine.phonetics.targets import (
    targets_from_phones as targets_from_phones,
)
from engine.phonetics.targets import (
    targets_from_points as targets_from_points,
)
from engine.phonetics.targets import (
    targets_from_text as targets_from_text,
)
from engine.phonetics.targets import (
    targets_from_textgrid as targets_from_textgrid,
)
from engine.phonetics.targets import (
    targets_from_utterance as targets_from_utterance,
)
from engine.recordings.corpus import (
    Corpus as Corpus,
)
from engine.recordings.corpus import (
    CorpusError as CorpusError,
)
from engine.recordings.corpus import (
    CorpusWarning as CorpusWarning,
)
from engine.recordings.corpus import (
    PhoneInterval as PhoneInterval,
)
from engine.recordings.corpus import (
    Utterance as Utterance,
)
from engine.recordings.corpus_blocks import (
    load_blocked as load_blocked,
)
from engine.recordings.corpus_blocks import (
    save_blocked as save_blocked,
)
from engine.synthesis.methods import (
    METHODS as METHODS,
)
from engine.synthesis.methods import (
    make_synthesizer as make_synthesizer,
)
from engine.synthesis.trajectory import (
    Trajectory as Trajectory,
)
from engine.talker.synthetic_talker import (
    SyntheticTalker as SyntheticTalker,
)
from engine.talker.talker_cache import (
    load_synthetic as load_synthetic,
)

__version__: str

__all__ = [
    "Corpus",
    "CorpusError",
    "CorpusWarning",
    "Hemisphere",
    "METHODS",
    "Manifold",
    "ManifoldFileError",
    "PhoneClusters",
    "PhoneInterval",
    "StateGraph",
    "SyntheticTalker",
    "Target",
    "TargetSequence",
    "Trajectory",
    "Utterance",
    "clusters_of",
    "evaluate_protocols",
    "hemisphere",
    "load_blocked",
    "load_synthetic",
    "make_synthesizer",
    "read_alignment",
    "read_corpus",
    "resample",
    "save_blocked",
    "targets_from_phones",
    "targets_from_points",
    "targets_from_text",
    "targets_from_textgrid",
    "targets_from_utterance",
]

def __dir__() -> list[str]: ...

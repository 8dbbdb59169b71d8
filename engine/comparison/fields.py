"""Per-utterance fields of a corpus: what a comparison's levels are read from.

A *field* names one categorical value per utterance (speaker, sex, emotion, text, session,
group, ...); its *levels* are the distinct values. :func:`utterance_fields` is the one
place where fields are read from a corpus; everything downstream takes the levels as
arrays, one string per utterance, with ``""`` for an unknown value.

Where the fields come from (``utterance_fields``):

* ``speaker``: :attr:`engine.recordings.corpus.Utterance.speaker` (always present);
* ``text``: :attr:`Utterance.text` (the sentence) when some utterance has one;
* every named field the corpus's utterances carry (``Utterance.fields``, read through
  :mod:`engine.recordings.metadata`: from file-name patterns and metadata tables at import,
  kept in corpus and manifold files). A field named ``text`` replaces the sentence.

:func:`attach_fields` sets fields on a corpus's utterances (the generated corpora of tests
and benchmarks use it).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from engine.recordings.metadata import field_names, with_fields
from engine.recordings.metadata import field_values as metadata_values

__all__ = ["FieldError", "utterance_fields", "attach_fields", "level_counts", "describe_fields", "field_values"]


class FieldError(ValueError):
    """A field or level asked for that the corpus does not have (the message names what it has)."""


def _as_values(values, n: int, name: str, where: str) -> np.ndarray:
    arr = np.asarray(["" if v is None else str(v) for v in values], dtype=object) \
        if not isinstance(values, str) else None
    if arr is None or arr.ndim != 1 or len(arr) != n:
        got = "a string" if arr is None else f"{len(arr)} values"
        raise FieldError(f"{where}: field {name!r} has {got}; expected one value per utterance ({n})")
    return np.asarray([s.strip() for s in arr], dtype=str) if n else np.zeros(0, dtype=str)


def utterance_fields(corpus) -> dict[str, np.ndarray]:
    """The per-utterance fields of ``corpus``: ``{name: ndarray of str, one per utterance}``.

    Parameters
    ----------
    corpus : engine.recordings.corpus.Corpus

    Returns
    -------
    dict of str to ndarray of shape (n_utterances,), dtype str
        Always ``speaker``; ``text`` when some utterance has one; then every field the
        corpus carries (module docstring). ``""`` is an unknown value.
    """
    utts = list(corpus.utterances)
    n = len(utts)
    name = getattr(corpus, "name", "corpus")
    out = {"speaker": _as_values([getattr(u, "speaker", "") for u in utts], n, "speaker", name)}
    texts = [getattr(u, "text", "") or "" for u in utts]
    if any(t.strip() for t in texts):
        out["text"] = _as_values(texts, n, "text", name)
    for key in field_names(corpus):
        if key != "speaker":
            out[key] = _as_values(metadata_values(corpus, key), n, key, name)
    return out


def attach_fields(corpus, fields: Mapping):
    """A shallow copy of ``corpus`` carrying ``fields`` where :func:`utterance_fields` reads them.

    Parameters
    ----------
    corpus : engine.recordings.corpus.Corpus
    fields : mapping of str to sequence of length n_utterances

    Returns
    -------
    Corpus
    """
    n = len(corpus.utterances)
    checked = {str(k): _as_values(v, n, str(k), getattr(corpus, "name", "corpus")) for k, v in fields.items()}
    utts = [with_fields(u, {k: v[i] for k, v in checked.items()}) for i, u in enumerate(corpus.utterances)]
    return replace(corpus, utterances=utts)


def level_counts(values) -> dict[str, int]:
    """``{level: utterances}`` of one field, most frequent first (ties by name), the unknown ``""`` left out."""
    vals, counts = np.unique(np.asarray(values, dtype=str), return_counts=True)
    order = sorted(range(len(vals)), key=lambda i: (-int(counts[i]), str(vals[i])))
    return {str(vals[i]): int(counts[i]) for i in order if str(vals[i]) != ""}


def describe_fields(fields: Mapping) -> str:
    """``speaker (2 levels), text (1 level)``: what a corpus offers, for messages."""
    parts = []
    for name, values in fields.items():
        k = len(level_counts(values))
        parts.append(f"{name} ({k} level{'s' if k != 1 else ''})")
    return ", ".join(parts) or "none"


def field_values(fields: Mapping, name: str, *, source: str = "the corpus") -> np.ndarray:
    """The values of field ``name``; :class:`FieldError` naming the fields there are when it is absent."""
    if name not in fields:
        raise FieldError(f"{source} has no field {name!r}; its fields: {describe_fields(fields)}. Fields come from "
                         "the corpus's metadata (speaker, text, and those read on import)")
    return np.asarray(fields[name], dtype=str)
